#!/usr/bin/env bash
# Runs every command the README shows in a ```sh block, as written, in the
# current directory (CI runs it in its copy of the tree with nothing beside
# it, after the tests, so the build is reused). `cargo test --release` is
# the step CI has just run and is skipped; `studio` serves until stopped, so
# it runs until it prints its address and is then stopped. Fails on the
# first command that fails, naming it.
set -euo pipefail
readme=${1:-README.md}
commands=$(awk '/^```sh$/ {on=1; next} /^```$/ {on=0} on' "$readme" | sed 's/[[:space:]]*#.*$//' | grep -v '^[[:space:]]*$')
n=0
while IFS= read -r cmd; do
  case "$cmd" in
    "cargo test --release") echo "== skip (CI's test step): $cmd"; continue ;;
  esac
  n=$((n + 1))
  echo "== $cmd"
  if [[ "$cmd" == *" studio"* ]]; then
    log=$(mktemp)
    # A port of its own, so a studio already running elsewhere does not clash.
    bash -c "$cmd --port 0" >"$log" 2>&1 &
    pid=$!
    for _ in $(seq 1 600); do
      grep -q 'studio: http://127.0.0.1:' "$log" && break
      kill -0 "$pid" 2>/dev/null || break
      sleep 0.5
    done
    cat "$log"
    ok=0; grep -q 'studio: http://127.0.0.1:' "$log" && ok=1
    pkill -P "$pid" 2>/dev/null || true
    kill "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
    rm -f "$log"
    [ "$ok" = 1 ] || { echo "README command failed: $cmd (no address printed)"; exit 1; }
  else
    bash -c "$cmd" || { echo "README command failed: $cmd"; exit 1; }
  fi
done <<<"$commands"
echo "== all $n README commands ran"
