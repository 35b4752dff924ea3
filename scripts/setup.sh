#!/usr/bin/env bash
# phonglab set-up: a usable libLLVM for Dr.Jit 1.5, then .venv with the pinned packages.
# Idempotent; `make setup` (and so `make demo` / `make test`) runs it.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}

# --- libLLVM: Dr.Jit 1.5 aborts with 15 and 16 and refuses < 17; Debian's libllvm19 works. ---
usable_llvm() {
  local f major
  for f in /usr/lib/*-linux-gnu/libLLVM*.so* /usr/lib/llvm-*/lib/libLLVM*.so* /usr/lib64/libLLVM*.so*; do
    [ -e "$f" ] || continue
    major=$(basename "$(readlink -f "$f")" | sed -nE 's/^libLLVM[-.](so\.)?([0-9]+).*/\2/p')
    [ -n "$major" ] || continue
    if [ "$major" -ge 17 ] && [ "$major" -ne 15 ] && [ "$major" -ne 16 ]; then echo "$f"; return 0; fi
  done
  return 1
}
if lib=$(usable_llvm); then
  echo "setup: usable libLLVM found: $lib"
elif [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
  echo "setup: no usable libLLVM (Dr.Jit 1.5 needs >= 17, not 15/16): installing Debian's libllvm19"
  export DEBIAN_FRONTEND=noninteractive
  apt-get install -y -qq libllvm19 >/dev/null 2>&1 || { apt-get update -qq && apt-get install -y -qq libllvm19; }
  lib=$(usable_llvm) || { echo "setup: libllvm19 did not install; phonglab will fall back to scalar_rgb (~150x slower)" >&2; }
else
  echo "setup: WARNING: no usable libLLVM and cannot install one (not root or no apt-get)." >&2
  echo "setup:          run 'sudo apt-get install -y libllvm19' (or set DRJIT_LIBLLVM_PATH to libLLVM >= 17, not 15/16);" >&2
  echo "setup:          until then phonglab falls back to scalar_rgb, where Python plugins are ~150x slower." >&2
fi

# --- the virtual environment with pinned packages ---
if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip >/dev/null 2>&1 || true
.venv/bin/python -m pip install -q -c constraints.txt -e ".[test]"
.venv/bin/python -m ipykernel install --sys-prefix --name python3 >/dev/null 2>&1 || true
.venv/bin/phonglab doctor || true
