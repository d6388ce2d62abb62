#!/usr/bin/env bash
# Install what demsweep needs and build the release binary. Idempotent: a second run changes
# nothing and takes seconds.
#   - LIGGGHTS 3.8 from Debian when `liggghts` is not on PATH (needs root or sudo);
#   - GNU parallel and GNU time, only for the benchmarks (BENCHMARKS.md);
#   - target/release/sweep.
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
echo "setup: ready: $(command -v liggghts), target/release/sweep" >&2
