#!/usr/bin/env bash
# Installs the Debian packages door_state_recognition needs, only when some are
# missing. Idempotent: a second run costs one dpkg query (well under a second).
set -euo pipefail

PKGS=(
  build-essential cmake catkin
  libroscpp-dev libnodeletlib-dev libnodeletlib-tools libnodelet-dev
  pluginlib-dev
  libpcl-dev libpcl-ros-dev libpcl-conversions-dev libeigen3-dev
  libtf2-ros-dev libtf2-eigen-dev libtf2-sensor-msgs-dev libtf2-geometry-msgs-dev
  ros-message-generation ros-message-runtime
  libstd-msgs-dev libsensor-msgs-dev libgeometry-msgs-dev libvisualization-msgs-dev
  python3-std-msgs python3-sensor-msgs python3-geometry-msgs python3-visualization-msgs
  ros-std-msgs ros-sensor-msgs ros-geometry-msgs ros-visualization-msgs
  librostest-dev python3-rostest python3-roslaunch python3-rosmaster
  python3-rostopic python3-rosnode python3-rosparam rosbash
  librosbag-dev python3-rosbag libgtest-dev python3-nose python3-numpy
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure
  libdiagnostic-updater-dev
  libtf2-msgs-dev librosbag-storage-dev
  nlohmann-json3-dev libyaml-cpp-dev
  rviz xvfb imagemagick
  libasan8 libubsan1
  clang-14 libclang-rt-14-dev
)

missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "install_deps: installing ${#missing[@]} missing Debian package(s): ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install_deps: done" >&2
