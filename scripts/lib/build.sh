# Sourced by the entry scripts: dependency install + configure + build in one place.
# Defines: MRVS_ROOT, MRVS_BUILD (build dir), MRVS_JOBS, step(), mrvs_build().

MRVS_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
MRVS_BUILD=${MRVS_BUILD_DIR:-$MRVS_ROOT/build}
MRVS_JOBS=${MRVS_JOBS:-$(nproc)}

step() { printf '\n== %s ==\n' "$*"; }

# mrvs_build [cmake --build args...]: installs missing packages, configures (Release),
# builds. On a configure failure prints the log and returns 1.
mrvs_build() {
  step "dependencies"
  "$MRVS_ROOT/scripts/install_deps.sh" || return 1
  step "configure ($MRVS_BUILD)"
  mkdir -p "$MRVS_BUILD"
  if ! cmake -S "$MRVS_ROOT" -B "$MRVS_BUILD" -DCMAKE_BUILD_TYPE=Release >"$MRVS_BUILD/configure.log" 2>&1; then
    cat "$MRVS_BUILD/configure.log"
    echo "configure failed (log above, also in $MRVS_BUILD/configure.log)" >&2
    return 1
  fi
  step "build (-j$MRVS_JOBS)"
  local start=$SECONDS
  cmake --build "$MRVS_BUILD" -j "$MRVS_JOBS" "$@" || return 1
  echo "build took $((SECONDS - start)) s"
}
