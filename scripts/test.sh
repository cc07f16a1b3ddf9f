#!/usr/bin/env bash
# Runs every check and test of the et repository. Works on a fresh machine: it installs what
# it needs (the thumbv7em-none-eabihf target, rustfmt, clippy, and Debian's qemu-system-arm)
# and is what CI (.ci/run) calls.
# Usage: ./scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."

# Each step's title, and how long the one before took (the figures in docs/measurements.md).
last=$SECONDS
step() {
  if [ -n "${title:-}" ]; then printf '   (%s: %d s)\n' "$title" $((SECONDS - last)); fi
  title=$1; last=$SECONDS
  printf '\n== %s\n' "$*"
}
trap 'if [ $? -eq 0 ] && [ -n "${title:-}" ]; then printf "   (%s: %d s; test.sh %d s in all)\n" "$title" $((SECONDS - last)) $SECONDS; fi' EXIT

step "toolchain: thumbv7em-none-eabihf target, rustfmt, clippy"
installed=$(rustup target list --installed)
grep -qx thumbv7em-none-eabihf <<<"$installed" || rustup target add thumbv7em-none-eabihf
components=$(rustup component list --installed)
for c in rustfmt clippy; do
  grep -q "^$c" <<<"$components" || rustup component add "$c"
done

step "qemu-system-arm (the firmware image's end-to-end test boots it)"
if ! command -v qemu-system-arm >/dev/null; then
  export DEBIAN_FRONTEND=noninteractive
  sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get install -y --no-install-recommends qemu-system-arm >/dev/null \
    || { $sudo apt-get update >/dev/null && $sudo apt-get install -y --no-install-recommends qemu-system-arm >/dev/null; }
fi
qemu-system-arm --version | head -1

step "format (cargo fmt --check)"
cargo fmt --all -- --check
(cd firmware && cargo fmt -- --check)

step "no import circles among the files of a crate (scripts/import_cycles.py)"
python3 scripts/import_cycles.py

# The Python module's environment (python/): a virtual environment with maturin, numpy and pytest
# from the package index, made in the background while the Rust builds below use the cores (it
# mostly waits on the network and the disk); its output is printed with the Python step.
venv=target/python-venv
python_setup_log=target/python-setup.log
python_setup() {
  if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv" 2>/dev/null || {
      # Debian's python3 keeps venv in its own package.
      sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
      $sudo apt-get install -y --no-install-recommends python3-venv >/dev/null \
        || { $sudo apt-get update >/dev/null && $sudo apt-get install -y --no-install-recommends python3-venv >/dev/null; }
      python3 -m venv "$venv"
    }
  fi
  "$venv/bin/python" -c "import numpy, pytest" 2>/dev/null && [ -x "$venv/bin/maturin" ] \
    || "$venv/bin/python" -m pip install -q --disable-pip-version-check "maturin>=1.9.4,<2" numpy pytest
}
mkdir -p target
python_setup >"$python_setup_log" 2>&1 &
python_setup_pid=$!

# Every build below compiles the workspace's own crates with clippy's lints, warnings as
# errors (scripts/clippy-rustc as cargo's RUSTC_WORKSPACE_WRAPPER): one compilation lints and
# builds each, where `cargo clippy` and then `cargo test` compiled every dependency twice. The
# cargo runs inside the tests (the QEMU image) inherit it, so they reuse what was built here.
export RUSTC_WORKSPACE_WRAPPER="$PWD/scripts/clippy-rustc"
# CI builds from an empty target folder once: incremental compilation's caches would only be
# written, never read (on a developer's machine they are kept for the next run).
if [ -n "${CI:-}" ]; then export CARGO_INCREMENTAL=0; fi

step "et-core builds no_std for the microcontroller (no default features)"
# (With the defmt feature it is built for the firmware just below.)
cargo build -p et-core --target thumbv7em-none-eabihf --no-default-features

step "firmware image, linted (cd firmware && cargo build --release), and the QEMU test image"
# The QEMU image is the release profile with the `qemu` feature (what `cargo build --profile
# qemu --features qemu` builds): built first and kept aside for the QEMU tests (ET_QEMU_IMAGE),
# then the board image, which reuses every compiled dependency (only the firmware crate is
# compiled again), where the qemu profile compiled all of them a second time.
(cd firmware && cargo build --release --features qemu)
qemu_image="$PWD/target/thumbv7em-none-eabihf/qemu-test/et-firmware"
mkdir -p "$(dirname "$qemu_image")"
cp target/thumbv7em-none-eabihf/release/et-firmware "$qemu_image"
(cd firmware && cargo build --release)
elf=target/thumbv7em-none-eabihf/release/et-firmware
if command -v size >/dev/null; then
  size -A "$elf" | awk '/^\.(vector_table|text|rodata|data) /{f+=$2} /^\.(data|bss|uninit) /{r+=$2}
    END {printf "firmware image: flash %d of 262144 bytes (program region), static RAM %d of 131072 bytes\n", f, r}'
fi

step "build and lint every target: libraries, programs, tests, examples, benchmarks"
cargo test --workspace --features et-host/viewer --no-run
cargo build --workspace --benches --features et-host/viewer

step "tests (cargo test --workspace --features et-host/viewer, its binaries side by side; the QEMU tests must run here), and beside them the Python module"
# scripts/run_tests.py runs cargo test's binaries as many at a time as there are cores (cargo
# runs them one after another, and several end on one long test that leaves a core idle) and
# prints a table of their times. The Python step runs beside them; its output follows theirs. `maturin develop` is `pip install ./python` without the wheel's release build. With
# the viewer feature (which the module does not use) every crate it shares with the test build
# above resolves with the same features (python/Cargo.toml, host/Cargo.toml say which), so only
# pyo3 and the module itself are compiled here.
python_log=target/python-tests.log
wait "$python_setup_pid" || { cat "$python_setup_log"; echo "setting up the Python environment failed"; exit 1; }
python_step() {
  cat "$python_setup_log"
  # cargo test first takes the build folder's lock to see that its build is fresh (under a
  # second); maturin's cargo, first, would hold it through its whole build of the module.
  sleep 5
  VIRTUAL_ENV="$PWD/$venv" "$venv/bin/maturin" develop -q -m python/Cargo.toml -F et-host/viewer
  ET_BIN="$PWD/target/debug/et" "$venv/bin/python" -m pytest -q python/tests
}
python_step >"$python_log" 2>&1 &
python_pid=$!
rust_tests=0
ET_REQUIRE_QEMU=1 ET_QEMU_IMAGE="$qemu_image" ET_BIN="$PWD/target/debug/et" \
  python3 scripts/run_tests.py --workspace --features et-host/viewer || rust_tests=$?
python_tests=0
wait "$python_pid" || python_tests=$?
printf '\n== Python module (python/), run beside the Rust tests: its output\n'
cat "$python_log"
if [ "$rust_tests" -ne 0 ]; then echo "the Rust tests failed (scripts/run_tests.py exited $rust_tests)"; fi
if [ "$python_tests" -ne 0 ]; then echo "the Python step failed (exit $python_tests)"; fi
[ "$rust_tests" -eq 0 ] && [ "$python_tests" -eq 0 ]
