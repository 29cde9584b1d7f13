#!/usr/bin/env bash
# The project's whole test suite, exactly what CI runs (.ci/run calls this script).
# It installs what the tests need first (libmujoco from the PyPI wheel), then checks
# formatting and lints with warnings as errors, then runs every test of every crate
# with every feature (the MuJoCo backend included).
set -euo pipefail
cd "$(dirname "$0")/.."

if [ -x scripts/install-mujoco.sh ]; then
    scripts/install-mujoco.sh
fi

# Doctests are linked in a temporary directory, where the $ORIGIN-relative rpath of
# .cargo/config.toml cannot reach third_party/; give rustdoc the absolute path.
export RUSTDOCFLAGS="-C link-args=-Wl,-rpath,$PWD/third_party/mujoco/lib"

echo "== cargo fmt --check"
cargo fmt --all -- --check

echo "== cargo clippy (warnings are errors)"
cargo clippy --workspace --all-targets --all-features --locked -- -D warnings

echo "== cargo test"
cargo test --workspace --all-features --locked

# FMPy is a real external FMI host: it imports the packaged FMUs as a user's tool would.
echo "== FMU hosts: FMPy"
python3 -m pip install --quiet --disable-pip-version-check "fmpy==0.3.32"
cargo build --quiet --locked -p plamo-fmu
cargo run --quiet --locked --all-features -- fmu build --out target/fmu-test
python3 fmus/tests/fmpy_host.py target/fmu-test
