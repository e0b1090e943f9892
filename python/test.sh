#!/usr/bin/env bash
# Builds the Python package into a virtual environment (target/python-venv) and runs its tests
# against the command line's binary (target/release/radiosity), built as `cargo test --release`
# builds it: `cargo build` resolves the dependencies' features without the tests' and would
# compile the library and the binary once more.
set -euo pipefail
cd "$(dirname "$0")/.."

venv=target/python-venv
if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
"$venv/bin/python" -m pip install -q --upgrade pip
started=$SECONDS
"$venv/bin/python" -m pip install -q "./python[test]"
echo "python/test.sh: the package built and installed in $((SECONDS - started)) s"
cargo test --release --no-run --quiet
"$venv/bin/python" -m pytest -q python/tests
