#!/usr/bin/env bash
# Installs the Debian 12 packages SimPartner needs, only those missing.
# Uses sudo when not root. Safe to run again.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libode-dev libtinyxml2-dev libsqlite3-dev libasio-dev libssl-dev zlib1g-dev libeigen3-dev
  qt6-base-dev libqt6opengl6-dev qt6-charts-dev libopenscenegraph-dev
  libxml2-utils xvfb xauth mesa-utils libgl1-mesa-dri imagemagick x11-apps
  python3 clang libclang-rt-14-dev
  desktop-file-utils lintian help2man liburdfdom-tools
  slurmctld slurmd slurm-client munge
  # The ROS component (ros/, docs/ros.md) and its tests: Debian's own ROS 1.
  ros-core python3-rosbag libroscpp-dev librosbag-dev libroslz4-dev libconsole-bridge-dev
  libstd-msgs-dev libgeometry-msgs-dev libnav-msgs-dev libsensor-msgs-dev libtrajectory-msgs-dev libtf2-msgs-dev
  pluginlib-dev libclass-loader-dev librcpputils-dev librcutils-dev libament-index-cpp-dev
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "install-deps: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
