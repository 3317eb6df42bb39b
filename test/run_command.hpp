// Running a command from a test: its exit code and what it printed.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <string>

struct CommandResult {
  int code;
  std::string out;
};

// Runs `cmd` through the shell (popen): what it writes to stdout, and its
// exit code (-1 when it did not exit normally or could not start).
inline CommandResult runCommand(const std::string& cmd) {
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return {-1, ""};
  std::string out;
  char buf[4096];
  while (std::size_t n = fread(buf, 1, sizeof buf, p)) out.append(buf, n);
  const int status = pclose(p);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}
