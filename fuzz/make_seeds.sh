#!/usr/bin/env bash
# Regenerates the seed corpora under fuzz/seeds/<target>/ (standard-library Python only).
# Seeds are small valid inputs that get each parser past its header checks; run_all.sh
# copies them into a scratch corpus, so this folder is never written by the fuzzer.
set -euo pipefail
exec python3 "$(dirname "$0")/make_seeds.py" "$@"
