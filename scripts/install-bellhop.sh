#!/usr/bin/env bash
# Installs the real BELLHOP ray/beam tracer (Acoustic Toolbox, Porter) for coopnav's acomms
# transmission-loss provider. The `aubellhop` wheel on PyPI ships a Linux bellhop.exe together
# with the Fortran runtime libraries it links against; we download the wheel for this platform,
# unpack the binary and its libraries into tools/bellhop/ at the repository root, and check that
# it runs. Idempotent: does nothing when tools/bellhop/bellhop.exe already works.
# coopnav finds the binary through $COOPNAV_BELLHOP, else tools/bellhop/bellhop.exe.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
dest="$root/tools/bellhop"
exe="$dest/bellhop.exe"

runs() {
  # BELLHOP with a missing environment file prints an error and exits; what matters is that the
  # dynamic loader resolves every library (exit 127 or a loader message otherwise).
  local out probe
  probe="$(mktemp -d)"
  out="$(cd "$probe" && LD_LIBRARY_PATH="$dest/lib:${LD_LIBRARY_PATH:-}" "$exe" coopnav_probe 2>&1 || true)"
  rm -rf "$probe"
  ! grep -qiE "error while loading shared libraries|not found|cannot execute" <<<"$out"
}

if [ -x "$exe" ] && runs; then
  echo "bellhop already installed at $exe"
  exit 0
fi

case "$(uname -m)" in
  x86_64) plat="manylinux2014_x86_64" ;;
  aarch64) plat="manylinux2014_aarch64" ;;
  *) echo "install-bellhop: unsupported machine $(uname -m); set COOPNAV_BELLHOP to a bellhop.exe" >&2; exit 1 ;;
esac

py="$(command -v python3 || command -v python || true)"
if [ -z "$py" ] || ! "$py" -m pip --version >/dev/null 2>&1; then
  echo "install-bellhop: python3 with pip is needed to download the aubellhop wheel from PyPI" >&2
  exit 1
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
# Try the common manylinux tags from newest to oldest; pip picks the wheel that matches.
"$py" -m pip download aubellhop --no-deps --only-binary=:all: --python-version 3.12 \
  --platform "$plat" --platform "manylinux_2_28_$(uname -m)" --platform "manylinux_2_17_$(uname -m)" \
  --platform "manylinux_2_34_$(uname -m)" --platform "manylinux_2_39_$(uname -m)" \
  -d "$tmp" -q
wheel="$(ls "$tmp"/*.whl | head -n 1)"
mkdir -p "$tmp/unpacked"
"$py" - "$wheel" "$tmp/unpacked" <<'PY'
import sys, zipfile
zipfile.ZipFile(sys.argv[1]).extractall(sys.argv[2])
PY
found="$(find "$tmp/unpacked" -type f -name 'bellhop.exe' | head -n 1)"
if [ -z "$found" ]; then
  echo "install-bellhop: no bellhop.exe inside $(basename "$wheel")" >&2
  exit 1
fi
rm -rf "$dest"
mkdir -p "$dest/lib"
cp "$found" "$exe"
chmod +x "$exe"
# Fortran runtime and friends: auditwheel puts them in <pkg>.libs/ (or a lib dir beside the exe).
find "$tmp/unpacked" -type f \( -name '*.so' -o -name '*.so.*' \) -exec cp {} "$dest/lib/" \;
echo "$(basename "$wheel")" > "$dest/SOURCE"
if ! runs; then
  echo "install-bellhop: $exe does not start (missing libraries?); see ldd output:" >&2
  LD_LIBRARY_PATH="$dest/lib" ldd "$exe" >&2 || true
  exit 1
fi
echo "bellhop installed at $exe (from $(cat "$dest/SOURCE"))"
