#!/usr/bin/env bash
# Installs Debian's chromium (the browser test of report.html runs it headless), if absent.
set -euo pipefail
bash "$(dirname "$0")/apt_install.sh" chromium /usr/bin/chromium
chromium --version
