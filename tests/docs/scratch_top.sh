# Sourced by the docs tests: scratch_top REPO BUILD_DIR SHARED_DIR WORK_DIR makes WORK_DIR/tpkit, a
# top-level folder as a user's clone has it (the repository's files linked, build/ the build under test)
# with WORK_DIR/shared beside it, and changes into it. Outputs the commands write land there, never in
# the repository.
scratch_top() {
  local repo=$1 build=$2 shared=$3 work=$4 f
  [ -x "$build/bin/tp-match" ] || { echo "$0: $build/bin: no tools built" >&2; return 2; }
  [ -d "$shared/data/pleiades-marseille" ] || { echo "$0: $shared/data/pleiades-marseille: missing" >&2; return 2; }
  rm -rf "$work"
  mkdir -p "$work/tpkit"
  for f in "$repo"/* "$repo"/.gitignore; do
    case $(basename "$f") in build* | examples-out | demo-out) continue ;; esac
    ln -s "$f" "$work/tpkit/"
  done
  ln -s "$build" "$work/tpkit/build"
  ln -s "$shared" "$work/shared"
  cd "$work/tpkit"
}
