#!/usr/bin/env bash
# apt_install.sh PACKAGE PATH: installs Debian's PACKAGE (as root, quietly) unless PATH, a file the
# package brings, is already there; then PATH must be there. The project's scripts that need a
# Debian package (install_chromium.sh, install_cgal_demo.sh) call this one.
set -euo pipefail
package="$1" path="$2"
if [ -e "$path" ]; then
  exit 0
fi
if [ "$(id -u)" != 0 ]; then
  echo "$path is missing: install it as root with apt-get install -y $package" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "$package" >/dev/null
[ -e "$path" ] || { echo "apt-get installed $package but $path is not there" >&2; exit 1; }
