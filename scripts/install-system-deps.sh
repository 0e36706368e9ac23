#!/usr/bin/env bash
# Debian packages EmoGen needs: offscreen OpenGL (EGL on Mesa llvmpipe), Chromium for the
# browser tests, PostgreSQL for the study server's second backend, Node.js for the front end,
# R with readr (the tests read every CSV output as an R user does: docs/data.md).
# Installs only what is missing; uses sudo when not root.
set -euo pipefail
PACKAGES=(libegl1 libegl-mesa0 libgl1-mesa-dri libgbm1 libgl1 chromium postgresql nodejs npm
  r-base-core r-cran-readr)
missing=()
for p in "${PACKAGES[@]}"; do
  if [ "$p" = nodejs ] || [ "$p" = npm ]; then
    command -v "${p/nodejs/node}" >/dev/null 2>&1 && continue
  fi
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
echo "installing Debian packages: ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
