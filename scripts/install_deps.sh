#!/usr/bin/env bash
# Installs the Debian 12 packages colorfree builds and runs with. Needs root (or sudo).
# Idempotent: does nothing when everything is there.
set -euo pipefail

packages=(
  build-essential cmake pkg-config git
  libmujoco-dev libqhull-dev libosmesa6-dev
  libopencv-dev libeigen3-dev libyaml-cpp-dev nlohmann-json3-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev
)
# Headless Chromium renders the HTML report to a PNG for checking it by eye; optional.
optional_packages=(chromium)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -eq 0 ]; then
  exit 0
fi
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
echo "install_deps: installing ${missing[*]}" >&2
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
if [ "${COLORFREE_WITH_CHROMIUM:-0}" = 1 ]; then
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq "${optional_packages[@]}" >&2
fi
