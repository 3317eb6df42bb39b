# Sourced by nodelet_latency.sh and soak_drive.sh (after REPO is set): the
# workspace's environment, the nodelet manager's environment as
# door_state.launch sets it, a roscore of their own, and stop(PID).
#   BUILD (DSR_BUILD or build/), BIN, OUT (= $BUILD/latency), ROS_MASTER_URI on a free port
# The manager runs with GOMP_SPINCOUNT=10000 (and glibc malloc's
# MALLOC_MMAP_THRESHOLD_ and MALLOC_TRIM_THRESHOLD_), as launch/door_state.launch
# starts it (argument omp_spincount), unless GOMP_SPINCOUNT or
# OMP_WAIT_POLICY is set in the environment (see nodelet_latency.sh).
BUILD="${DSR_BUILD:-$REPO/build}"
BIN="$BUILD/bin"
OUT="$BUILD/latency"
mkdir -p "$OUT"
export PATH=/usr/bin:$PATH
set +u; source "$BUILD/.ws/devel/setup.bash"; set -u
export ROS_LOG_DIR="$OUT/log"
if [ -z "${GOMP_SPINCOUNT:-}" ] && [ -z "${OMP_WAIT_POLICY:-}" ]; then export GOMP_SPINCOUNT=10000; fi
# glibc malloc as door_state.launch sets it (util/keep_freed_memory.hpp), unless the environment sets it.
if [ -z "${MALLOC_MMAP_THRESHOLD_:-}${MALLOC_TRIM_THRESHOLD_:-}${MALLOC_TOP_PAD_:-}${GLIBC_TUNABLES:-}" ]; then
  export MALLOC_MMAP_THRESHOLD_=67108864 MALLOC_TRIM_THRESHOLD_=1073741824
fi
PORT="${LATENCY_ROS_PORT:-$((20000 + RANDOM % 20000))}"
export ROS_MASTER_URI="http://localhost:$PORT"

stop() {  # stop PID: SIGINT, then wait for it (only processes the caller started)
  local pid="$1"
  [ -n "$pid" ] || return 0
  kill -INT "$pid" 2>/dev/null || true
  for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
  kill -KILL "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
}

start_roscore() {  # start_roscore LOG: a roscore on $PORT, its PID in CORE; exit 1 if it does not come up
  roscore -p "$PORT" >"$1" 2>&1 &
  CORE=$!
  for _ in $(seq 150); do rosparam list >/dev/null 2>&1 && break; sleep 0.2; done
  rosparam list >/dev/null 2>&1 || { echo "$(basename "$0"): roscore on port $PORT did not come up" >&2; exit 1; }
}
