# Shared by the scripts in this folder: paths, messages, root helpers.
# shellcheck shell=bash
MESHMEND_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${MESHMEND_BUILD_DIR:-$MESHMEND_ROOT/build}"
PREFIX="$BUILD_DIR/meshlab-prefix"          # private MeshLab with our plugins
FUZZ_DIR="${MESHMEND_FUZZ_BUILD_DIR:-$BUILD_DIR-fuzz}"  # sanitized build (scripts/fuzz)
DEPS_DIR="$MESHMEND_ROOT/.deps"              # unpacked MeshLab source (ignored by git)
SHARED_DIR="$(cd "$MESHMEND_ROOT/.." && pwd)/shared"
SYSTEM_MESHLAB_LIB=/usr/lib/x86_64-linux-gnu/meshlab
JOBS="${MESHMEND_JOBS:-$(nproc)}"
# Third-party builds (scripts/hosts) and the compiler cache live outside the
# clone, shared by every clone and run on the machine.
CACHE="${MESHMEND_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/meshmend}"
export CCACHE_DIR="${CCACHE_DIR:-$CACHE/ccache}"
export CCACHE_MAXSIZE="${CCACHE_MAXSIZE:-8G}"
# Paths inside the clone hashed relative to it: another clone's build hits
# the cache too.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$MESHMEND_ROOT}"

say() { printf '\033[1m==> %s\033[0m\n' "$*"; }
note() { printf '    %s\n' "$*"; }
die() { printf 'error: %s\n' "$*" >&2; exit 1; }

# Runs a command as root (directly, or through sudo when available).
as_root() {
  if [ "$(id -u)" = 0 ]; then "$@"
  elif command -v sudo >/dev/null; then sudo "$@"
  else die "root is needed to run: $* (install the packages listed in scripts/setup, or run as root)"
  fi
}

seconds_since() { echo $(( $(date +%s) - $1 )); }
