#!/usr/bin/env bash
# Builds the Python package into a virtual environment (target/python-venv) and runs its tests
# against the command line's binary (target/release/radiosity, built by `cargo test --release`
# or `cargo build --release`).
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
cargo build --release --bin radiosity
"$venv/bin/python" -m pytest -q python/tests
