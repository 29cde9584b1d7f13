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
# The same features as the test build above, so nothing is compiled twice; the packager
# ships libmujoco next to a MuJoCo-built library.
cargo build --quiet --locked --all-features -p plamo-fmu
cargo run --quiet --locked --all-features -- fmu build --out target/fmu-test
python3 fmus/tests/fmpy_host.py target/fmu-test
# The FMU's 1000 instantiate/free cycles (and full initialise/step cycles) once more
# under valgrind (Debian's), next to the counting-allocator check of the test itself.
if ! command -v valgrind >/dev/null; then
    sudo_=""
    [ "$(id -u)" -eq 0 ] || sudo_="sudo"
    $sudo_ apt-get update -qq
    $sudo_ apt-get install -y -qq --no-install-recommends valgrind >/dev/null
fi
leaks_bin=$(cargo test --locked --all-features -p plamo-fmu --test leaks --no-run 2>&1 |
    sed -n 's/.*Executable tests\/leaks.rs (\(.*\))$/\1/p')
valgrind --quiet --leak-check=full --show-leak-kinds=definite,indirect \
    --errors-for-leak-kinds=definite,indirect --error-exitcode=9 \
    "$leaks_bin" --test-threads=1

# ---- Replay exports and viewer (issue 9) ----------------------------------------
# The real tools check the exports of the playground route on both backends: the
# Khronos glTF validator (npm), an independent BVH reader (PyPI `bvh`), the MCAP
# project's reader (PyPI `mcap`), and Debian's
# headless Chromium (never a downloaded browser build) driving the viewer page
# through playwright-core.
echo "== replay exports and viewer: glTF validator, BVH reader, headless Chromium"
viewer_apt=""
command -v chromium >/dev/null || viewer_apt="chromium"
command -v npm >/dev/null || viewer_apt="$viewer_apt nodejs npm"
if [ -n "$viewer_apt" ]; then
    sudo_=""
    [ "$(id -u)" -eq 0 ] || sudo_="sudo"
    $sudo_ apt-get update -qq
    # shellcheck disable=SC2086  # a list of package names
    $sudo_ apt-get install -y -qq --no-install-recommends $viewer_apt >/dev/null
fi
python3 -m pip install --quiet --disable-pip-version-check "bvh==0.3" "mcap==1.6.0"
PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --prefix orchestrator/viewer --no-audit --no-fund --loglevel=error
npm run --silent build --prefix orchestrator/viewer
viewer_out=target/viewer-test
rm -rf "$viewer_out"
for physics in rapier mujoco; do
    # The route times out by design (exit status 1, see README); anything else fails.
    status=0
    cargo run --quiet --locked --all-features -- run --scene playground --quiet \
        --instructions "Run from the tree to the car, then crawl to the bench" \
        --max-seconds 8 --physics "$physics" --out "$viewer_out/$physics" || status=$?
    if [ "$status" -gt 1 ] || [ ! -f "$viewer_out/$physics/replay.glb" ]; then
        echo "plamo run --physics $physics failed (status $status) or wrote no replay.glb"
        exit 1
    fi
done
node orchestrator/viewer/test/validate-gltf.mjs "$viewer_out"/*/replay.glb
python3 orchestrator/tests/viewer/check_bvh.py "$viewer_out/rapier" "$viewer_out/mujoco"
python3 orchestrator/tests/viewer/check_mcap.py "$viewer_out/rapier" "$viewer_out/mujoco"
cargo run --quiet --locked --all-features -- view "$viewer_out/rapier" "$viewer_out/mujoco" \
    --write-html "$viewer_out/view.html"
node orchestrator/viewer/test/browser.mjs "$viewer_out/view.html" "$viewer_out/screenshots"
