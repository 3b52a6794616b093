#!/usr/bin/env bash
# Installs Debian's libcgal-demo, if absent: CGAL's data archive
# (/usr/share/doc/libcgal-dev/data.tar.gz) holds real scans nobody here made; the integration test
# tests/it/real_scan.rs maps, fits, optimises, exports and reports one of them (hippo1.ply).
set -euo pipefail
bash "$(dirname "$0")/apt_install.sh" libcgal-demo /usr/share/doc/libcgal-dev/data.tar.gz
