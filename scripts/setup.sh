#!/usr/bin/env bash
# Install what demsweep needs and build the release binary. Idempotent: a second run changes
# nothing and takes seconds.
#   - LIGGGHTS 3.8 from Debian when `liggghts` is not on PATH (needs root or sudo);
#   - GNU parallel and GNU time, only for the benchmarks (BENCHMARKS.md);
#   - target/release/sweep, linked as `sweep` into a directory on PATH: next to `cargo`
#     (~/.cargo/bin with rustup), else /usr/local/bin, so that `sweep ...` works as written.
set -euo pipefail
cd "$(dirname "$0")/.."

as_root() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; elif command -v sudo >/dev/null; then sudo "$@"; else
    echo "setup: need root (or sudo) to run: $*" >&2; exit 1; fi
}

missing=()
command -v liggghts >/dev/null 2>&1 || missing+=(liggghts)
command -v parallel >/dev/null 2>&1 || missing+=(parallel)
[ -x /usr/bin/time ] || missing+=(time)
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]} from Debian" >&2
  as_root apt-get update -qq
  # --no-install-recommends: without it apt pulls ParaView and a desktop stack for liggghts.
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
command -v liggghts >/dev/null || { echo "setup: liggghts is still not on PATH" >&2; exit 1; }

cargo build --release --quiet

# A link, not a copy: a later `cargo build --release` in this checkout updates the command.
on_path() { case ":$PATH:" in *":$1:"*) return 0 ;; *) return 1 ;; esac; }
bin_dir=$(dirname "$(command -v cargo)")
case "$bin_dir" in "$HOME"/*) ;; *) bin_dir=/usr/local/bin ;; esac  # never into /usr/bin
if ! on_path "$bin_dir" || [ ! -w "$bin_dir" ]; then bin_dir=/usr/local/bin; fi
as_root_if_needed() { if [ -w "$bin_dir" ]; then "$@"; else as_root "$@"; fi; }
as_root_if_needed ln -sfn "$PWD/target/release/sweep" "$bin_dir/sweep"
found=$(command -v sweep || true)
if [ "$found" != "$bin_dir/sweep" ]; then
  echo "setup: warning: \`sweep\` on PATH is ${found:-missing}, not $bin_dir/sweep" >&2
fi
echo "setup: ready: $(command -v liggghts), $bin_dir/sweep -> $PWD/target/release/sweep" >&2
