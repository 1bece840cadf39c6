# Sourced by the scripts: sets $target to the folder cargo builds into, as
# cargo itself resolves it (CARGO_TARGET_DIR, a build.target-dir setting,
# or target/ at the workspace root), so that the scripts find their
# binaries wherever a shared build cache or a CI set-up puts them.
target=$(cargo metadata --format-version 1 --no-deps \
    | sed -n 's/.*"target_directory":"\([^"]*\)".*/\1/p')
if [ -z "$target" ]; then
    echo "error: cargo metadata gave no target_directory" >&2
    exit 1
fi
# Inside the repository, relative: reports name their inputs by it.
case "$target" in
    "$PWD"/*) target=${target#"$PWD"/} ;;
esac
