#!/usr/bin/env bash
# Installs Chromium from Debian's packages for coopnav's real-browser test of replay.html
# (crates/cli/tests/moos.rs opens it headless). Quiet and idempotent: does nothing when
# /usr/bin/chromium already runs.
set -euo pipefail
if [ -x /usr/bin/chromium ] && /usr/bin/chromium --version >/dev/null 2>&1; then
  exit 0
fi
sudo=""
if [ "$(id -u)" -ne 0 ]; then
  sudo="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq chromium chromium-driver >/dev/null
/usr/bin/chromium --version
