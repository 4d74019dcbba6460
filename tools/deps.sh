#!/bin/sh
# Install the Debian packages named on the command line when they are missing.
# Root: apt-get directly; with password-less sudo: through sudo; otherwise print
# the exact command to run and fail, so that make stops with a clear reason.
# With --check first: install nothing, only name what is missing (plain make).
check_only=0
[ "$1" = --check ] && { check_only=1; shift; }
# not a Debian system: nothing to ask; the compiler will say what is missing
command -v dpkg-query >/dev/null 2>&1 || exit 0
missing=""
for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing="$missing $p"
done
[ -z "$missing" ] && exit 0
if [ $check_only = 1 ]; then
    echo "ampath: missing Debian packages:$missing" >&2
    echo "run:    sudo apt-get update && sudo apt-get install -y$missing   (or: make check / make demo, which install them)" >&2
    exit 1
fi
if ! command -v apt-get >/dev/null 2>&1; then
    echo "ampath: missing packages:$missing (no apt-get here: install them with your package manager)" >&2
    exit 1
fi
if [ "$(id -u)" = 0 ]; then
    SUDO=""
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
    SUDO="sudo"
else
    echo "ampath: missing Debian packages:$missing" >&2
    echo "run:    sudo apt-get update && sudo apt-get install -y$missing" >&2
    exit 1
fi
echo "ampath: installing Debian packages:$missing" >&2
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get install -y --no-install-recommends $missing >/dev/null 2>&1 ||
    { $SUDO apt-get update -qq && $SUDO apt-get install -y --no-install-recommends $missing; }
