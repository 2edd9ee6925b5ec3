#!/usr/bin/env bash
# Drives a breeding run on Kubernetes: one Indexed Job per generation, then
# `leafmagic merge`. Run it where both kubectl and the run volume are at
# hand (a driver pod that mounts the claim at /runs and whose service
# account may create, watch and delete Jobs; or a workstation with the
# volume mounted at /runs). Needs leafmagic, kubectl and envsubst (Debian:
# gettext-base) on PATH.
#
#   deploy/k8s/breed.sh RUN SHARDS IMAGE -- BREED_SETTINGS...
#   e.g. deploy/k8s/breed.sh floaters 64 registry.example/leafmagic:0.1 -- \
#          --population 10000 --generations 8 --seconds 10
#
# Resumable: run it again after any failure; finished generations are in the
# checkpoint, finished shards of the current one are kept (--skip-done), and
# `leafmagic merge` of a merged generation does nothing.
set -euo pipefail
[ $# -ge 4 ] && [ "$4" = "--" ] || {
  echo "usage: $0 RUN SHARDS IMAGE -- BREED_SETTINGS..." >&2
  exit 2
}
export RUN=$1 SHARDS=$2 IMAGE=$3
shift 4
export CLAIM=${CLAIM:-leafmagic-runs}
ROOT=${RUNS_ROOT:-/runs}
DIR=$ROOT/$RUN
HERE=$(cd "$(dirname "$0")" && pwd)

if [ ! -f "$DIR/run.toml" ]; then
  leafmagic breed "$@" --out "$DIR" --create-only
fi
generations=$(sed -n 's/^generations = //p' "$DIR/run.toml" | head -n1)
while :; do
  # The next generation: one after the checkpoint's (0 without one).
  next=0
  if [ -f "$DIR/checkpoint.json" ]; then
    # The checkpoint's own field comes first (history and archive follow).
    last=$(grep -o '"generation":[0-9]*' "$DIR/checkpoint.json" | head -n1 | cut -d: -f2)
    next=$((last + 1))
  fi
  [ "$next" -lt "$generations" ] || break
  export GENERATION=$next
  echo "generation $GENERATION: Indexed Job of $SHARDS pods" >&2
  kubectl delete job "leafmagic-gen-$GENERATION" --ignore-not-found --wait=true >/dev/null
  envsubst <"$HERE/shard-job.yaml" | kubectl apply -f - >/dev/null
  # Complete, or failed (an index out of retries): merge says which shard.
  kubectl wait --for=condition=complete --timeout=24h "job/leafmagic-gen-$GENERATION" ||
    echo "job leafmagic-gen-$GENERATION did not complete; merging to see which shards are missing" >&2
  leafmagic merge "$DIR" --generation "$GENERATION" --count "$SHARDS"
  kubectl delete job "leafmagic-gen-$GENERATION" --ignore-not-found >/dev/null
done
echo "run complete: $DIR" >&2
