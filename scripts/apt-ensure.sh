#!/usr/bin/env bash
# Installs the given Debian packages when they are missing (through sudo when not root).
#   scripts/apt-ensure.sh pkg [pkg...]
set -euo pipefail
missing=()
for pkg in "$@"; do
  if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$pkg")
  fi
done
((${#missing[@]})) || exit 0
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "apt: installing ${missing[*]}"
apt_install() { $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"; }
if ! apt_install; then
  $SUDO apt-get update -q
  apt_install
fi
