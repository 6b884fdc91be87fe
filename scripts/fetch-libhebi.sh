#!/usr/bin/env bash
# Fetches HEBI's C library (libhebi 2.27.0) from the pinned hebi-py 2.16.1 on PyPI,
# checks both checksums, and puts the versioned library in DEST (default target/hebi/).
# x86-64: from the manylinux wheel; aarch64 (a Jetson or Raspberry Pi tether PC): from
# the sdist, which carries both. The library is loaded at run time and never committed
# (HEBI ships no licence with it). Usage: scripts/fetch-libhebi.sh [DEST]; ARCH=aarch64
# fetches the other architecture's. Prints the library's path. .ci/run and the HEBI
# tests call it (docs/hebi.md).
set -euo pipefail

VERSION=2.16.1
LIB=libhebi.so.2.27.0
arch=${ARCH:-$(uname -m)}
case $arch in
    x86_64)
        FILE=hebi_py-${VERSION}-py3-none-manylinux_2_35_x86_64.whl
        FILE_SHA256=e137d9b5e7d0a5a102aeca4fe233485f49da52d29f6b8da948d7e4f60e3b5481
        MEMBER=hebi/lib/$LIB
        LIB_SHA256=95a95fa85e0b95902d95593b8af4c6a74c8f291b299f9eed8d6886eff6e74262
        PIP_ARGS=(--only-binary=:all:)
        ;;
    aarch64)
        FILE=hebi_py-${VERSION}.tar.gz
        FILE_SHA256=360f37df0f85fb8c9d6f0fcc5427666eeb3fced215109128f5545720c516bffe
        MEMBER=hebi_py-${VERSION}/src/hebi/lib/linux_aarch64/$LIB
        LIB_SHA256=623cc36dccc19ca6c3a15bd600b0c59c9143b3679d65cac69abc7e798bcb8a1a
        PIP_ARGS=(--no-binary=:all:)
        ;;
    *)
        echo "fetch-libhebi: no libhebi for $arch (x86_64 and aarch64 only)" >&2
        exit 1
        ;;
esac

dest=${1:-"$(dirname "$0")/../target/hebi"}
[[ $arch == "$(uname -m)" ]] || dest="$dest/$arch"
mkdir -p "$dest"
if [[ -f "$dest/$LIB" ]] && echo "$LIB_SHA256  $dest/$LIB" | sha256sum -c --quiet - 2>/dev/null; then
    realpath "$dest/$LIB"
    exit 0
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 -m pip download -q --disable-pip-version-check --no-deps "${PIP_ARGS[@]}" \
    "hebi-py==$VERSION" -d "$work" >&2
echo "$FILE_SHA256  $work/$FILE" | sha256sum -c --quiet - >&2
# The unversioned names in the package are small text files, not links: take the
# versioned one. Extracted by Python, never imported.
python3 - "$work/$FILE" "$work/out" "$MEMBER" <<'PY'
import sys, tarfile, zipfile
archive, out, member = sys.argv[1:]
if archive.endswith(".whl"):
    zipfile.ZipFile(archive).extract(member, out)
else:
    with tarfile.open(archive) as t:
        try:
            t.extract(member, out, filter="data")
        except TypeError:  # Python before 3.12 without the backport: one named member
            t.extract(member, out)
PY
echo "$LIB_SHA256  $work/out/$MEMBER" | sha256sum -c --quiet - >&2
mv "$work/out/$MEMBER" "$dest/$LIB"
realpath "$dest/$LIB"
