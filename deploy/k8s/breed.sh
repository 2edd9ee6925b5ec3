#!/usr/bin/env bash
# Drives a breeding run on Kubernetes: one Indexed Job per generation, then
# `leafmagic merge`. Run it where both kubectl and the run volume are at
# hand (the driver pod of driver-pod.yaml, which mounts the claim at /runs
# under a service account of rbac.yaml; or a workstation with the volume
# mounted at /runs). Needs leafmagic, kubectl and envsubst (Debian:
# gettext-base) on PATH.
#
#   deploy/k8s/breed.sh RUN SHARDS IMAGE -- BREED_SETTINGS...
#   e.g. deploy/k8s/breed.sh floaters 64 registry.example/leafmagic:0.1 -- \
#          --population 10000 --generations 8 --seconds 10 --max-work 4e10
#
# Each generation's Job is leafmagic-NAME-gen-G (NAME: RUN as a DNS label,
# render.sh), so runs in one namespace never delete each other's Jobs. The
# driver waits until the Job is Complete or Failed (polling every
# POLL_SECONDS, 10; giving up after TIMEOUT_SECONDS, 86400): on Failed (an
# index out of retries) it stops with a non-zero status and that index's
# log. Resumable: run it again after any failure; finished generations are
# in the checkpoint, finished shards of the current one are kept
# (--skip-done), and `leafmagic merge` of a merged generation does nothing.
set -euo pipefail
[ $# -ge 4 ] && [ "$4" = "--" ] || {
  echo "usage: $0 RUN SHARDS IMAGE -- BREED_SETTINGS..." >&2
  exit 2
}
export RUN=$1 SHARDS=$2 IMAGE=$3
shift 4
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=${RUNS_ROOT:-/runs}
DIR=$ROOT/$RUN
POLL=${POLL_SECONDS:-10}
TIMEOUT=${TIMEOUT_SECONDS:-86400}
NAME=$(bash "$HERE/render.sh" name)
export NAME

# The first True condition that ends a Job: Complete or Failed (newer
# clusters set SuccessCriteriaMet / FailureTarget first).
job_state() {
  kubectl get job "$1" -o jsonpath='{range .status.conditions[?(@.status=="True")]}{.type}{"\n"}{end}' 2>/dev/null |
    awk '$1 == "Complete" || $1 == "SuccessCriteriaMet" {print "Complete"; exit}
         $1 == "Failed" || $1 == "FailureTarget" {print "Failed"; exit}'
}

# Prints what failed: the first failed index (with backoffLimitPerIndex) or
# any failed pod, and that pod's log.
report_failure() {
  local job=$1 generation=$2 indexes index selector pod
  indexes=$(kubectl get job "$job" -o jsonpath='{.status.failedIndexes}' 2>/dev/null || true)
  index=${indexes%%[,-]*}
  selector="job-name=$job"
  [ -n "$index" ] && selector="$selector,batch.kubernetes.io/job-completion-index=$index"
  pod=$(kubectl get pods -l "$selector" --sort-by=.metadata.creationTimestamp \
    -o jsonpath='{range .items[*]}{.metadata.name}{" "}{.status.phase}{"\n"}{end}' 2>/dev/null |
    awk '$2 == "Failed" {p = $1} END {print p}')
  if [ -n "$index" ]; then
    echo "generation $generation: Job $job failed: shard $index of $SHARDS ran out of retries (failed indexes: $indexes)" >&2
  else
    echo "generation $generation: Job $job failed (the Job names no failed index: its backoffLimit was reached)" >&2
  fi
  if [ -n "$pod" ]; then
    echo "--- log of pod $pod (last 100 lines) ---" >&2
    kubectl logs "$pod" --tail=100 >&2 || echo "(the log could not be read)" >&2
    echo "--- end of log ---" >&2
  else
    echo "no failed pod is left to show a log (ttlSecondsAfterFinished may have removed it)" >&2
  fi
  echo "fix the cause and run $0 again: finished shards are kept" >&2
}

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
  job=leafmagic-$NAME-gen-$GENERATION
  echo "generation $GENERATION: Indexed Job $job of $SHARDS pods" >&2
  kubectl delete job "$job" --ignore-not-found --wait=true >/dev/null
  bash "$HERE/render.sh" job | kubectl apply -f - >/dev/null
  started=$SECONDS
  state=$(job_state "$job")
  while [ -z "$state" ]; do
    if [ $((SECONDS - started)) -ge "$TIMEOUT" ]; then
      echo "generation $GENERATION: Job $job neither complete nor failed after ${TIMEOUT} s; giving up (run $0 again to go on waiting)" >&2
      exit 1
    fi
    sleep "$POLL"
    state=$(job_state "$job")
  done
  if [ "$state" = Failed ]; then
    report_failure "$job" "$GENERATION"
    exit 1
  fi
  leafmagic merge "$DIR" --generation "$GENERATION" --count "$SHARDS"
  kubectl delete job "$job" --ignore-not-found >/dev/null
done
echo "run complete: $DIR" >&2
