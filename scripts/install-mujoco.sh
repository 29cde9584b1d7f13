#!/usr/bin/env bash
# Installs the MuJoCo 3.17.0 native library (the version mujoco-rs =7.0.0 binds) into
# third_party/mujoco/lib/ from the PyPI wheel. Idempotent: does nothing when the
# library and its symlink are already there. Needs python3 + pip and a registry.
set -euo pipefail

VERSION=3.17.0
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
LIB_DIR="$ROOT/third_party/mujoco/lib"
LIB="$LIB_DIR/libmujoco.so.$VERSION"

if [[ -f "$LIB" && -L "$LIB_DIR/libmujoco.so" ]]; then
    echo "install-mujoco: $LIB already present"
    exit 0
fi

case "$(uname -s)-$(uname -m)" in
    Linux-x86_64) ;;
    *) echo "install-mujoco: only Linux x86_64 is supported (got $(uname -s)-$(uname -m))" >&2; exit 1 ;;
esac

TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT

# Pin the cp311 manylinux_2_28 x86_64 wheel so the choice does not depend on the local
# Python version (the .so inside is the same for every CPython tag).
python3 -m pip download --quiet --no-deps "mujoco==$VERSION" \
    --only-binary=:all: --platform manylinux_2_28_x86_64 --python-version 3.11 \
    --implementation cp --abi cp311 -d "$TMP"

WHEEL="$(ls "$TMP"/mujoco-"$VERSION"-*.whl | head -n 1)"
mkdir -p "$LIB_DIR"
python3 - "$WHEEL" "$LIB_DIR" "$VERSION" <<'PY'
import sys, zipfile, shutil, os
wheel, out, version = sys.argv[1:]
name = f"mujoco/libmujoco.so.{version}"
with zipfile.ZipFile(wheel) as z, z.open(name) as src, open(os.path.join(out, f"libmujoco.so.{version}.part"), "wb") as dst:
    shutil.copyfileobj(src, dst)
PY
mv "$LIB.part" "$LIB"
ln -sfn "libmujoco.so.$VERSION" "$LIB_DIR/libmujoco.so"
echo "install-mujoco: installed $LIB"
