#!/usr/bin/env bash
# Renders one of the manifests of this folder for a run, to stdout:
#
#   deploy/k8s/render.sh name|job|volume|rbac|driver [-- BREED_SETTINGS...]
#
# From the environment: RUN (the run directory's name inside the volume),
# SHARDS, IMAGE, GENERATION (job), STORAGE_CLASS (volume; empty: the
# cluster's default class), CLAIM (default leafmagic-NAME). NAME is RUN made
# a DNS label (lower case, [a-z0-9-], at most 44 characters so that a Job
# name leafmagic-NAME-gen-NNNN stays within 63), with a hash of RUN when it
# had to be shortened. Only the variables named here are substituted.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
what=${1:?usage: $0 name|job|volume|rbac|driver [-- BREED_SETTINGS...]}
shift

name_of() {
  local n
  n=$(printf '%s' "$1" | tr 'A-Z' 'a-z' | tr -c 'a-z0-9-' '-' | sed -e 's/^-*//' -e 's/-*$//' -e 's/--*/-/g')
  if [ ${#n} -gt 44 ] || [ "$n" != "$1" ]; then
    local h
    h=$(printf '%s' "$1" | cksum | cut -d' ' -f1)
    n="$(printf '%s' "${n:0:34}" | sed 's/-*$//')-$(printf '%08x' "$h" | cut -c1-8)"
  fi
  [ -n "$n" ] || n=run
  printf '%s' "$n"
}

: "${RUN:?RUN must be set (the run directory inside the volume)}"
export NAME=${NAME:-$(name_of "$RUN")}
export CLAIM=${CLAIM:-leafmagic-$NAME}
case $what in
  name) printf '%s\n' "$NAME" ;;
  job)
    : "${SHARDS:?}" "${IMAGE:?}" "${GENERATION:?}"
    envsubst '$RUN $NAME $GENERATION $SHARDS $IMAGE $CLAIM' <"$HERE/shard-job.yaml"
    ;;
  volume)
    export STORAGE_CLASS=${STORAGE_CLASS:-}
    if [ -z "$STORAGE_CLASS" ]; then
      sed '/storageClassName:/d' "$HERE/volume.yaml"
    else
      cat "$HERE/volume.yaml"
    fi | envsubst '$NAME $CLAIM $STORAGE_CLASS'
    ;;
  rbac) envsubst '$NAME' <"$HERE/rbac.yaml" ;;
  driver)
    : "${SHARDS:?}" "${IMAGE:?}"
    [ "${1:-}" = "--" ] && shift
    SETTINGS=""
    for a in "$@"; do
      # One YAML list item per setting, double-quoted and escaped.
      esc=${a//\\/\\\\}
      esc=${esc//\"/\\\"}
      SETTINGS+="        - \"$esc\""$'\n'
    done
    export SETTINGS=${SETTINGS%$'\n'}
    envsubst '$NAME $RUN $SHARDS $IMAGE $CLAIM $SETTINGS' <"$HERE/driver-pod.yaml"
    ;;
  *)
    echo "$0: unknown manifest '$what' (name, job, volume, rbac or driver)" >&2
    exit 2
    ;;
esac
