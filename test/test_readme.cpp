// The README's reference tables against the files they describe: every
// parameter of config/default.yaml and cfg/DoorState.cfg in the parameter
// table with the same default and type, the nodelet's own parameters there
// too, every launch argument with its default, every message field and
// constant, and every option the tools' --help prints. A README row for a
// parameter no file has yet (a feature documented ahead of its merge) is
// allowed and printed.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "run_command.hpp"

namespace {

const std::string kSource = DSR_SOURCE_DIR;

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << "cannot read " << path;
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream is(text);
  for (std::string l; std::getline(is, l);) out.push_back(l);
  return out;
}

std::vector<std::string> cells(const std::string& row) {
  std::vector<std::string> out;
  std::string cur;
  for (std::size_t i = 1; i < row.size(); ++i) {  // skip the leading '|'
    if (row[i] == '\\' && i + 1 < row.size() && row[i + 1] == '|') {
      cur += '|';
      ++i;
    } else if (row[i] == '|') {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += row[i];
    }
  }
  for (auto& c : out) {
    const auto a = c.find_first_not_of(' '), b = c.find_last_not_of(' ');
    c = a == std::string::npos ? "" : c.substr(a, b - a + 1);
  }
  return out;
}

// `x` -> x, "" -> (empty), "+z" -> +z.
std::string unquote(std::string s) {
  if (s.size() >= 2 && s.front() == '`' && s.back() == '`') s = s.substr(1, s.size() - 2);
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
  return s;
}

bool sameValue(const std::string& a, const std::string& b) {
  if (a == b) return true;
  try {
    std::size_t ia = 0, ib = 0;
    const double x = std::stod(a, &ia), y = std::stod(b, &ib);
    return ia == a.size() && ib == b.size() && std::abs(x - y) <= 1e-12 * std::max(1.0, std::abs(x));
  } catch (const std::exception&) {
    return false;
  }
}

struct ReadmeParam {
  std::string type, default_value, unit, range, default_cell;
};

// The README's parameter table: rows whose first cell is `~name`.
std::map<std::string, ReadmeParam> readmeParameters() {
  std::map<std::string, ReadmeParam> out;
  for (const auto& l : lines(readFile(kSource + "/README.md"))) {
    if (l.rfind("| `~", 0) != 0) continue;
    const auto c = cells(l);
    if (c.size() < 6) {
      ADD_FAILURE() << "parameter row with fewer than 6 cells: " << l;
      continue;
    }
    const std::string name = unquote(c[0]).substr(1);
    EXPECT_EQ(out.count(name), 0u) << "~" << name << " twice in the README";
    out[name] = {c[1], unquote(c[2]), c[3], c[4], c[2]};
  }
  return out;
}

struct CfgParam {
  std::string type, default_value;
};

std::map<std::string, CfgParam> cfgParameters() {
  std::map<std::string, CfgParam> out;
  static const std::regex add(R"re(gen\.add\("(\w+)",\s*(\w+)_t,\s*\d+,\s*"(?:[^"\\]|\\.)*",\s*("[^"]*"|[^,\)]+))re");
  const std::string text = readFile(kSource + "/cfg/DoorState.cfg");
  for (std::sregex_iterator it(text.begin(), text.end(), add), stop; it != stop; ++it)
    out[(*it)[1]] = {(*it)[2], unquote((*it)[3])};
  return out;
}

}  // namespace

TEST(Readme, ParameterTableHasEveryParameterOfTheYamlAndTheCfgWithTheirDefaults) {
  const auto readme = readmeParameters();
  const auto cfg = cfgParameters();
  const YAML::Node yaml = YAML::LoadFile(kSource + "/config/default.yaml");
  ASSERT_GT(cfg.size(), 30u) << "cfg/DoorState.cfg not parsed";
  ASSERT_GT(yaml.size(), 30u);
  std::set<std::string> known;
  for (const auto& kv : yaml) {
    const std::string name = kv.first.as<std::string>(), value = kv.second.as<std::string>();
    known.insert(name);
    const auto r = readme.find(name);
    if (r == readme.end()) {
      ADD_FAILURE() << "config/default.yaml's " << name << " is not in the README's parameter table";
      continue;
    }
    EXPECT_TRUE(sameValue(r->second.default_value, value))
        << "~" << name << ": README default " << r->second.default_value << ", config/default.yaml " << value;
  }
  const std::map<std::string, std::string> types = {{"str", "string"}, {"double", "double"}, {"int", "int"}};
  for (const auto& [name, p] : cfg) {
    known.insert(name);
    const auto r = readme.find(name);
    if (r == readme.end()) {
      ADD_FAILURE() << "cfg/DoorState.cfg's " << name << " is not in the README's parameter table";
      continue;
    }
    EXPECT_TRUE(sameValue(r->second.default_value, p.default_value))
        << "~" << name << ": README default " << r->second.default_value << ", cfg " << p.default_value;
    EXPECT_EQ(r->second.type, types.at(p.type)) << "~" << name;
  }
  // The nodelet's own parameters (those it checks by name at start).
  const std::string nodelet = readFile(kSource + "/src/ros/nodelet_parameters.cpp");
  static const std::regex own(R"re(if \(name == "(\w+)"\))re");
  std::size_t own_count = 0;
  for (std::sregex_iterator it(nodelet.begin(), nodelet.end(), own), stop; it != stop; ++it, ++own_count) {
    known.insert((*it)[1]);
    EXPECT_EQ(readme.count((*it)[1]), 1u) << "the nodelet's own ~" << (*it)[1] << " is not in the README's table";
  }
  EXPECT_GE(own_count, 3u) << "fixed_frame, tf_queue_size, diagnostic_period at least";
  for (const auto& [name, p] : readme) {
    if (!known.count(name)) std::cout << "[ note     ] README documents ~" << name << ", which no file defines yet\n";
    EXPECT_FALSE(p.type.empty()) << "~" << name << " has no type";
    EXPECT_FALSE(p.default_cell.empty()) << "~" << name << " has no default";
  }
}

TEST(Readme, LaunchTableHasEveryArgumentWithItsDefault) {
  // The README's launch table: | file | argument | default | meaning |, the
  // file cell empty on the rows after its first.
  std::map<std::string, std::map<std::string, std::string>> readme;  // file -> argument -> default
  std::string file;
  for (const auto& l : lines(readFile(kSource + "/README.md"))) {
    if (l.rfind("| ", 0) != 0) {
      file.clear();
      continue;
    }
    const auto c = cells(l);
    if (c.size() < 4) continue;
    if (std::regex_match(c[0], std::regex("`[a-z_]+\\.launch`"))) file = unquote(c[0]);
    else if (!c[0].empty()) file.clear();
    if (!file.empty() && c[1].size() > 2 && c[1][0] == '`') readme[file][unquote(c[1])] = unquote(c[2]);
  }
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kSource + "/launch")) {
    const std::string name = entry.path().filename().string();
    if (entry.path().extension() != ".launch") continue;
    ++files;
    SCOPED_TRACE(name);
    ASSERT_EQ(readme.count(name), 1u) << name << " has no rows in the README's launch table";
    const std::string text = readFile(entry.path().string());
    static const std::regex arg(R"re(<arg\s+name="(\w+)"(?:\s+default="([^"]*)")?\s*/>)re");
    for (std::sregex_iterator it(text.begin(), text.end(), arg), stop; it != stop; ++it) {
      const std::string a = (*it)[1];
      std::string def = (*it)[2].matched ? (*it)[2].str() : "(required)";
      def = std::regex_replace(def, std::regex(R"(\$\(find door_state_recognition\)/)"), "");
      const auto r = readme[name].find(a);
      if (r == readme[name].end()) {
        ADD_FAILURE() << name << "'s argument " << a << " is not in the README";
        continue;
      }
      EXPECT_EQ(r->second, def) << name << " " << a;
    }
  }
  EXPECT_GE(files, 2u);
}

TEST(Readme, MessageTableHasEveryFieldAndConstant) {
  const std::string text = readFile(kSource + "/README.md");
  // Field rows: | `a`, `b` | type | meaning |
  std::map<std::string, std::string> fields;  // name -> type cell
  for (const auto& l : lines(text)) {
    if (l.rfind("| `", 0) != 0) continue;
    const auto c = cells(l);
    if (c.size() != 3) continue;
    static const std::regex name_re("`(\\w+)`");
    for (std::sregex_iterator it(c[0].begin(), c[0].end(), name_re), stop; it != stop; ++it) fields[(*it)[1]] = c[1];
  }
  for (const std::string msg : {"DoorState", "DoorStateArray"}) {
    SCOPED_TRACE(msg);
    EXPECT_NE(text.find("`" + msg + "`"), std::string::npos);
    for (const auto& l : lines(readFile(kSource + "/msg/" + msg + ".msg"))) {
      const std::string code = l.substr(0, l.find('#'));
      std::smatch m;
      if (std::regex_match(code, m, std::regex(R"(\s*(\w+)\s+([A-Z_]+)\s*=\s*(\d+)\s*)"))) {
        EXPECT_NE(text.find("`" + m[2].str() + "`=" + m[3].str()), std::string::npos) << m[2] << "=" << m[3];
      } else if (std::regex_match(code, m, std::regex(R"(\s*([\w/]+(?:\[\d*\])?)\s+(\w+)\s*)"))) {
        if (msg == "DoorStateArray") {  // header and doors are told in prose
          EXPECT_NE(text.find("`" + m[2].str() + "`"), std::string::npos) << m[2];
          continue;
        }
        const auto f = fields.find(m[2]);
        if (f == fields.end()) {
          ADD_FAILURE() << msg << "." << m[2] << " is not in the README's message table";
          continue;
        }
        EXPECT_EQ(f->second, m[1].str()) << msg << "." << m[2];
      }
    }
  }
}

TEST(Readme, EveryOptionOfTheToolsHelpIsInTheReadme) {
  const std::string text = readFile(kSource + "/README.md");
  for (const std::string tool : {"door_state_cli", "door_scene_sim", "door_state_eval"}) {
    SCOPED_TRACE(tool);
    const CommandResult help = runCommand(std::string(DSR_BIN_DIR) + "/" + tool + " --help");
    ASSERT_EQ(help.code, 0);
    static const std::regex opt("(^|[\\s\\[|,])(--[a-z][-a-z0-9]*)");
    std::set<std::string> options;
    for (std::sregex_iterator it(help.out.begin(), help.out.end(), opt), stop; it != stop; ++it) options.insert((*it)[2]);
    EXPECT_GE(options.size(), 3u) << help.out;
    for (const auto& o : options) {
      const std::regex in_readme(o + "(?![-a-z0-9])");
      EXPECT_TRUE(std::regex_search(text, in_readme)) << tool << " " << o << " is not in the README";
    }
  }
}

TEST(Readme, StaysAManualOfAtMost400LinesWithTheTwoCommandsFirst) {
  const auto l = lines(readFile(kSource + "/README.md"));
  EXPECT_LE(l.size(), 400u);
  std::size_t demo = 0, test = 0;
  for (std::size_t i = 0; i < l.size() && i < 60; ++i) {
    if (l[i].find("make demo") != std::string::npos && !demo) demo = i + 1;
    if (l[i].find("make test") != std::string::npos && !test) test = i + 1;
  }
  EXPECT_GT(demo, 0u) << "make demo in the first 60 lines";
  EXPECT_GT(test, 0u) << "make test in the first 60 lines";
  // Every relative link points at a file that exists.
  const std::string text = readFile(kSource + "/README.md");
  static const std::regex link(R"(\]\(((?:doc|config|cfg|launch|msg)/[^)#\s]+)(?:#[^)]*)?\))");
  for (std::sregex_iterator it(text.begin(), text.end(), link), stop; it != stop; ++it)
    EXPECT_TRUE(std::filesystem::exists(kSource + "/" + (*it)[1].str())) << (*it)[1];
  // And every relative link of doc/*.md.
  static const std::regex doc_link(R"(\]\(([^)#\s:]+)(?:#[^)]*)?\))");
  std::size_t docs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(kSource + "/doc")) {
    if (entry.path().extension() != ".md") continue;
    ++docs;
    const std::string doc = readFile(entry.path().string());
    for (std::sregex_iterator it(doc.begin(), doc.end(), doc_link), stop; it != stop; ++it)
      EXPECT_TRUE(std::filesystem::exists(entry.path().parent_path() / (*it)[1].str()))
          << entry.path().filename() << " links " << (*it)[1];
  }
  EXPECT_GE(docs, 4u) << "doc/ holds results, benchmarks, method, development";
}
