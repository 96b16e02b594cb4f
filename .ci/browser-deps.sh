#!/bin/sh
# Installs what tests/report/test_browser.py needs on a fresh Debian machine:
# the Debian Chromium package (/usr/bin/chromium), driven by the playwright
# Python package from the venv. Nothing is downloaded from outside the Debian
# archive (never "playwright install"). Run as root.
set -eu
export DEBIAN_FRONTEND=noninteractive
apt-get update
apt-get install -y --no-install-recommends chromium fonts-dejavu-core
test -x /usr/bin/chromium
/usr/bin/chromium --version || true
