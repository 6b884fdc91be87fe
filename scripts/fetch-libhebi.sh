#!/usr/bin/env bash
# Fetches HEBI's C library (libhebi) for x86-64 Linux from the pinned hebi-py wheel on
# PyPI, checks both checksums, and puts the versioned library in DEST (default
# target/hebi/). The library is loaded at run time and never committed (HEBI ships no
# licence with it). Usage: scripts/fetch-libhebi.sh [DEST]; prints the library's path.
# Issue 46: `.ci/run` and the tests will call this.
set -euo pipefail

VERSION=2.16.1
WHEEL=hebi_py-${VERSION}-py3-none-manylinux_2_35_x86_64.whl
WHEEL_SHA256=e137d9b5e7d0a5a102aeca4fe233485f49da52d29f6b8da948d7e4f60e3b5481
LIB=libhebi.so.2.27.0
LIB_SHA256=95a95fa85e0b95902d95593b8af4c6a74c8f291b299f9eed8d6886eff6e74262

dest=${1:-"$(dirname "$0")/../target/hebi"}
mkdir -p "$dest"
if [[ -f "$dest/$LIB" ]] && echo "$LIB_SHA256  $dest/$LIB" | sha256sum -c --quiet - 2>/dev/null; then
    realpath "$dest/$LIB"
    exit 0
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 -m pip download -q --disable-pip-version-check --no-deps --only-binary=:all: \
    "hebi-py==$VERSION" -d "$work" >&2
echo "$WHEEL_SHA256  $work/$WHEEL" | sha256sum -c --quiet - >&2
# The wheel's unversioned names are small text files, not links: take the versioned one.
python3 - "$work/$WHEEL" "$work" "$LIB" <<'PY'
import sys, zipfile
wheel, out, lib = sys.argv[1:]
zipfile.ZipFile(wheel).extract(f"hebi/lib/{lib}", out)
PY
echo "$LIB_SHA256  $work/hebi/lib/$LIB" | sha256sum -c --quiet - >&2
mv "$work/hebi/lib/$LIB" "$dest/$LIB"
realpath "$dest/$LIB"
