#!/usr/bin/env bash
# leafmagic against MuJoCo on the same work, measured side by side in one run.
#
#   bash benches/vs-mujoco.sh [LEAFMAGIC_BINARY] [ROUNDS]
#
# MuJoCo (PyPI `mujoco`, installed into a virtual environment under
# target/vs-mujoco-venv on first use; the script skips with a message where
# it cannot install) simulates a rigid card falling in still air with its
# ellipsoid fluid model (quadratic drag, Kutta and Magnus lift, added mass,
# angular drag), RK4 at 1/1200 s: the set-up of tests/data/mujoco-falls
# (4 x 2 cm, 0.2 mm, 600 kg/m^3, released tilted 20 and 2 degrees).
#
# Two comparisons, each interleaved over ROUNDS (default 5) rounds:
# - one 10 s fall: MuJoCo's card (mj_step over 12,000 steps in C, no Python
#   per step) against `leafmagic drop a --seconds 10` (its own stepping wall
#   time, `wall_s` of --json, and the whole process);
# - the default breed (100 leaves x 8 generations of 10 s falls, each leaf
#   from 4 release attitudes; elites are not dropped again: 730 leaves, 2,920
#   falls, 29,200 leaf-seconds) on all cores, against MuJoCo simulating the
#   same 29,200 card-seconds on as many processes as
#   cores (each process times a 100 s slice; the total is extrapolated from
#   the measured rate, which is constant per step).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
bin=$(realpath "${1:-$repo/target/release/leafmagic}")
rounds=${2:-5}
venv=$repo/target/vs-mujoco-venv
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import mujoco" 2>/dev/null; then
  echo "== installing mujoco into $venv"
  if ! { python3 -m venv "$venv" && "$venv/bin/pip" install -q mujoco; } >/dev/null 2>&1; then
    echo "skipped: cannot install the PyPI package mujoco (no network or no wheel for this machine)"
    exit 0
  fi
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$venv/bin/python" - "$bin" "$rounds" "$work" <<'EOF'
import json, os, statistics, subprocess, sys, time
import mujoco

binary, rounds, work = sys.argv[1], int(sys.argv[2]), sys.argv[3]
cores = os.cpu_count() or 1

CARD = """
<mujoco>
  <option timestep="{dt}" integrator="RK4" density="1.2" viscosity="1.8e-5" gravity="0 0 -9.80665"/>
  <worldbody>
    <body name="card" quat="{quat}">
      <freejoint/>
      <geom type="box" size="0.02 0.01 0.0001" density="600" fluidshape="ellipsoid"/>
    </body>
  </worldbody>
</mujoco>
"""

def card_model():
    import math
    a, b = math.radians(20) / 2, math.radians(2) / 2
    # Tilted 20 degrees about body x, then 2 degrees about body y.
    qx = (math.cos(a), math.sin(a), 0.0, 0.0)
    qy = (math.cos(b), 0.0, math.sin(b), 0.0)
    w1, x1, y1, z1 = qx
    w2, x2, y2, z2 = qy
    q = (w1*w2 - x1*x2 - y1*y2 - z1*z2, w1*x2 + x1*w2 + y1*z2 - z1*y2,
         w1*y2 - x1*z2 + y1*w2 + z1*x2, w1*z2 + x1*y2 - y1*x2 + z1*w2)
    return mujoco.MjModel.from_xml_string(CARD.format(dt=1/1200, quat=" ".join(map(str, q))))

def mujoco_seconds(model, simulated):
    """Wall seconds for `simulated` seconds of the card, stepping in C."""
    data = mujoco.MjData(model)
    steps = round(simulated / model.opt.timestep)
    t = time.perf_counter()
    mujoco.mj_step(model, data, nstep=steps)
    wall = time.perf_counter() - t
    assert abs(data.time - simulated) < 1e-6 and all(map(lambda v: v == v, data.qpos))
    return wall

def leafmagic_drop():
    t = time.perf_counter()
    out = subprocess.run([binary, "drop", "a", "--seconds", "10", "--json"],
                         check=True, capture_output=True, text=True).stdout
    whole = time.perf_counter() - t
    return json.loads(out)["wall_s"], whole

def leafmagic_breed(k):
    d = os.path.join(work, f"breed-{k}")
    t = time.perf_counter()
    subprocess.run([binary, "breed", "--out", d], check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t
    subprocess.run(["rm", "-rf", d])
    return wall

def mujoco_parallel_rate(slice_s):
    """Card-seconds per wall second with one process per core."""
    code = ("import mujoco,sys,time\n"
            f"m=mujoco.MjModel.from_xml_string({CARD.format(dt=1/1200, quat='1 0 0 0')!r})\n"
            "d=mujoco.MjData(m);t=time.perf_counter()\n"
            f"mujoco.mj_step(m,d,nstep={round(slice_s * 1200)})\n"
            "print(time.perf_counter()-t)\n")
    t = time.perf_counter()
    procs = [subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
             for _ in range(cores)]
    for p in procs:
        p.communicate()
    return cores * slice_s / (time.perf_counter() - t)

model = card_model()
mujoco_seconds(model, 1.0)  # warm-up
drop_mj, drop_lm, drop_lm_whole, breed_lm, breed_mj = [], [], [], [], []
# 730 leaves (elites are not dropped again), each from 4 release attitudes
# (`--releases`, default 4 since issue 19), 10 s each.
LEAF_SECONDS = 730 * 4 * 10.0
for r in range(rounds):
    drop_mj.append(mujoco_seconds(model, 10.0))
    s, w = leafmagic_drop()
    drop_lm.append(s)
    drop_lm_whole.append(w)
    breed_lm.append(leafmagic_breed(r))
    breed_mj.append(LEAF_SECONDS / mujoco_parallel_rate(100.0))

med = statistics.median
def show(name, v):
    return f"{name:<44} {med(v):10.4f} s  ({min(v):.4f}–{max(v):.4f})"
print(f"{rounds} interleaved rounds, {cores} cores; wall seconds: median (min–max)")
print(show("MuJoCo card, one 10 s fall (stepping)", drop_mj))
print(show("leafmagic drop a, 10 s (stepping, wall_s)", drop_lm))
print(show("leafmagic drop a, 10 s (whole process)", drop_lm_whole))
print(show(f"MuJoCo card, {LEAF_SECONDS:.0f} card-s on {cores} processes", breed_mj))
print(show("leafmagic default breed (2,920 falls)", breed_lm))
ratios = [m / l for m, l in zip(drop_mj, drop_lm)]
print(f"one 10 s fall: leafmagic {med(ratios):.1f}x MuJoCo (stepping; rounds {min(ratios):.1f}–{max(ratios):.1f}); "
      f"{med([m / l for m, l in zip(drop_mj, drop_lm_whole)]):.1f}x counting leafmagic's whole process")
ratios = [m / l for m, l in zip(breed_mj, breed_lm)]
print(f"default breed: leafmagic {med(ratios):.1f}x MuJoCo on the same leaf-seconds (rounds {min(ratios):.1f}–{max(ratios):.1f})")
EOF
