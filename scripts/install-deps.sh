#!/usr/bin/env bash
# Install the run-time libraries arbvis and its tests need on Debian/Ubuntu, where missing:
# Mesa's EGL and llvmpipe (the default offscreen backend, no GPU needed), libOSMesa (the
# second backend, loaded at run time), Xvfb and the X libraries winit opens (the viewer and
# its tests); and, to build the default `zfp` feature (ZFP-compressed MDIO, through zarrs'
# zfp-sys: the zfp C library built with cmake, its bindings made with libclang), cmake and
# libclang; and Chromium (Debian's, with its driver), the browser the notebook view's tests
# open (python/tests/test_notebook_browser.py). Uses sudo when not root. .ci/run and
# scripts/test.sh call it.
set -euo pipefail

packages=(libegl1 libegl-mesa0 libgl1 libgl1-mesa-dri libglx-mesa0 libosmesa6 xvfb xauth
          libx11-xcb1 libxkbcommon0 libxkbcommon-x11-0 libxcursor1 libxi6 libxrandr2
          cmake libclang-dev chromium)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -eq 0 ]; then
  exit 0
fi
if ! command -v apt-get >/dev/null; then
  echo "arbvis needs these Debian packages (or your system's equivalents): ${missing[*]}" >&2
  exit 1
fi
sudo=()
if [ "$(id -u)" -ne 0 ]; then
  sudo=(sudo)
fi
echo "installing: ${missing[*]}"
"${sudo[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
