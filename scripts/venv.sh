# Sourced by scripts/setup and scripts/test (bash): the shared Python environments, and .venv/ over one.
#
# The locked packages are installed once per set of lock files in $cache/venv-<hash of the files and the
# Python version>, shared by every checkout and by CI: requirements.lock (scripts/setup: the package's
# dependencies and its build tools, no torch), and requirements.lock with requirements-test.lock
# (scripts/test: pybullet, torch, stable-baselines3, Ray, pytest, ...; torch from PyPI is a ~3 GB CUDA
# build). .venv/ is the checkout's own small environment layered over one of them
# (scripts/layer_venv.py): it holds the checkout's editable snakesim install.
# Needs: $python, and say() for progress lines.

cache=${SNAKESIM_VENV_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/snakesim}

# shared_venv_path LOCK...: where the environment of these lock files lives (made or not).
shared_venv_path() {
  local hash
  hash=$( (cat "$@"; "$python" -c 'import sys; print(sys.version)') | sha256sum | cut -c1-16)
  echo "$cache/venv-$hash"
}

# shared_venv LOCK...: the environment holding exactly these lock files, made if missing; prints its path.
shared_venv() {
  local base requirements=() lock
  base=$(shared_venv_path "$@")
  for lock in "$@"; do requirements+=(-r "$lock"); done
  if [ ! -f "$base/.complete" ]; then
    say "creating the Python environment $base from $* (first time: downloads, minutes)" >&2
    rm -rf "$base"
    mkdir -p "$cache"
    "$python" -m venv "$base"
    "$base/bin/pip" install -q --upgrade pip >&2
    "$base/bin/pip" install -q "${requirements[@]}" >&2
    touch "$base/.complete"
  fi
  # The shared environment holds the locked packages only. `maturin develop` writes a .pth naming the
  # checkout it ran in, so installing snakesim there would send every other checkout's `import snakesim`
  # to the last one set up (or to a deleted clone). Earlier versions of scripts/setup did that.
  if [ -n "$(ls -d "$base"/lib/python3*/site-packages/snakesim*.dist-info 2>/dev/null)" ]; then
    "$base/bin/pip" uninstall -q -y snakesim >&2
  fi
  echo "$base"
}

# layer_dot_venv BASE LOCK...: .venv/ (made if missing) over the shared environment BASE of these locks;
# a .venv/ of your own (not made by scripts/setup) gets the locks installed into it instead.
layer_dot_venv() {
  local base=$1 requirements=() lock
  shift
  for lock in "$@"; do requirements+=(-r "$lock"); done
  [ -L .venv ] && rm .venv  # earlier versions linked .venv to the shared environment
  if [ ! -e .venv ]; then
    "$python" -m venv .venv
    touch .venv/.snakesim-layered
  fi
  if [ -f .venv/.snakesim-layered ]; then
    "$python" scripts/layer_venv.py .venv "$base" >/dev/null
  else
    echo "note: .venv/ is a directory of your own; installing $* into it"
    .venv/bin/pip install -q "${requirements[@]}"
  fi
}
