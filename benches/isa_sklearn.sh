#!/usr/bin/env bash
# Issue #24: `btf compress` on every kernel path this CPU runs (BTF_SIMD=scalar|avx2|avx512)
# against scikit-learn's PCA on the same view slots, in one run. See benches/isa_sklearn.py
# for what is measured; this wrapper installs scikit-learn and numpy (PyPI) if missing and
# builds btf-core's fit_slots example (the like-for-like fits) if it is not built.
#
#   benches/isa_sklearn.sh STORE.btf [K] [OUT_DIR]
#
# STORE: an f16 BTF store (an f32 store is converted to f16 first with btf-core's
#   `convert_store` example when it is built: `cargo build --release -p btf-core --example
#   convert_store`); K: view slots exported for scikit-learn (default 9, spread over the
#   rings); OUT_DIR: where outputs, timings and the report go (default /tmp/isa_sklearn.PID;
#   the eigen stores are deleted after each run, the exported slots at the end).
# Environment: BTF (the btf binary; default $CARGO_TARGET_DIR/release/btf, else
#   target/release/btf), ROUNDS (rounds of the paths, interleaved; default 1),
#   PATHS (e.g. "avx2 avx512"; default every path the CPU runs), COMPRESS_ARGS (added to
#   every `btf compress`, e.g. "--codec none"), SKLEARN_THREADS (BLAS
#   threads of scikit-learn, through OPENBLAS/OMP/MKL_NUM_THREADS; default: the library's
#   own choice, all cores — on a loaded machine its spinning threads inflate its times).
# Example, quiet machine: benches/quiet.sh benches/isa_sklearn.sh /tmp/bench/corduroy256_f16.btf
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
if ! python3 -c "import sklearn, numpy" 2>/dev/null; then
  echo "installing scikit-learn and numpy from PyPI" >&2
  python3 -m pip install --quiet scikit-learn numpy threadpoolctl
fi
if [ -n "${SKLEARN_THREADS:-}" ]; then # read by the BLAS libraries when they load
  export OPENBLAS_NUM_THREADS=$SKLEARN_THREADS OMP_NUM_THREADS=$SKLEARN_THREADS MKL_NUM_THREADS=$SKLEARN_THREADS
fi
fit="${FIT_SLOTS:-${CARGO_TARGET_DIR:-target}/release/examples/fit_slots}"
if [ ! -x "$fit" ]; then # the like-for-like fits (isa_sklearn.py, step 4)
  echo "building btf-core's fit_slots example" >&2
  cargo build --release --quiet -p btf-core --example fit_slots
fi
exec python3 "$here/isa_sklearn.py" "$@"
