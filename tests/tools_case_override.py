#!/usr/bin/env python3
"""tools/case_override.py's list paths, on a copy of cases/dam_break_obstacle_plane_2d.yaml:
- `bodies.obstacle.size=[...]` changes the element named obstacle, `bodies.0.radius=...` the first;
- `bodies.gate={...}` with no element named gate appends one named gate (the rest as given), so a
  variant with an extra body, block or probe is one command (a gate lifted from the floor:
  docs/bench/impact_pressure.md); a second `bodies.gate.velocity=...` then changes it;
- a scalar for a missing name, a map naming another element and a missing index are refused
  (exit 2, the path and the names that exist in the message).
usage: tools_case_override.py SRC_DIR WORK_DIR. Exit 0, or 1 with what failed."""
import os
import subprocess
import sys

src, work = sys.argv[1], sys.argv[2]
tools = os.path.join(src, "tools")
sys.path.insert(0, tools)
import case_override  # noqa: E402

case = os.path.join(src, "cases", "dam_break_obstacle_plane_2d.yaml")
os.makedirs(work, exist_ok=True)
failures = []


def run(*overrides):
    out = os.path.join(work, "v.yaml")
    p = subprocess.run([sys.executable, os.path.join(tools, "case_override.py"), case, out, *overrides],
                       capture_output=True, text=True)
    return p.returncode, p.stderr, (case_override.load_case(out) if p.returncode == 0 else None)


def expect(cond, what):
    if not cond:
        failures.append(what)


rc, err, doc = run("bodies.obstacle.size=[0.2, 0.2]", "bodies.0.radius=0.003",
                   "bodies.gate={shape: box, motion: prescribed, material: wall, radius: 0.002, size: [0.02, 0.62], "
                   "position: [1.98, 0.312], velocity: [0, 2]}", "bodies.gate.velocity=[0, 4]")
expect(rc == 0, f"the overrides were refused: {err}")
if doc:
    names = [b["name"] for b in doc["bodies"]]
    expect(names == ["floor", "wall_xmin", "wall_xmax", "obstacle", "gate"], f"bodies are {names}")
    by = {b["name"]: b for b in doc["bodies"]}
    expect(by["obstacle"]["size"] == [0.2, 0.2], "obstacle.size not changed")
    expect(doc["bodies"][0]["radius"] == 0.003, "bodies.0.radius not changed")
    expect(by.get("gate", {}).get("velocity") == [0, 4], "the added gate's velocity not changed by the later path")
    expect(by.get("gate", {}).get("motion") == "prescribed", "the added gate lost its keys")
for bad, msg in [("bodies.gat.radius=1", "no element named 'gat' (names: floor, wall_xmin, wall_xmax, obstacle)"),
                 ("bodies.gate=3", "no element named 'gate'"),
                 ("bodies.gate={name: door, shape: box}", "no element named 'gate'"),
                 ("bodies.7={shape: box}", "index 7 out of range")]:
    rc, err, _ = run(bad)
    expect(rc == 2 and msg in err, f"{bad}: exit {rc}, message {err.strip()!r}, expected 2 and {msg!r}")
for f in failures:
    print("tools_case_override:", f)
print("tools_case_override:", "FAIL" if failures else "ok")
sys.exit(1 if failures else 0)
