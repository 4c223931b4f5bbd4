#!/bin/sh
# Markdown rows of the validation table in cases/README.md from `lahar check` output directories
# (each holding check.json and summary.json; validation_check.sh writes them to OUT/run):
# case, dx, particles, steps, each metric value against its bound, pass, simulation wall time.
# usage: validation_table.sh RUN_DIR...
exec python3 - "$@" <<'PY'
import json, os, re, sys
print("| case | dx [m] | particles | steps | metrics (value / bound) | pass | wall [s] |")
print("|---|---|---|---|---|---|---|")
for d in sys.argv[1:]:
    try:
        chk = json.load(open(os.path.join(d, "check.json")))
        summ = json.load(open(os.path.join(d, "summary.json")))
    except (OSError, ValueError) as e:
        print(f"| {d} | | | | no result ({e.__class__.__name__}) | no | |")
        continue
    case = chk.get("case", d)
    dx, name = "", os.path.basename(case)
    try:
        text = open(case).read()
        m = re.search(r"^\s+dx:\s*([^\s#]+)", text, re.M)
        dx = m.group(1) if m else ""
        m = re.match(r"# from (\S+) by tests/validation_check.sh:(.*)", text)
        name = m.group(1) + (" (" + m.group(2).strip() + ")" if m and m.group(2).strip() else "") if m else name
    except OSError:
        pass
    detail = summ.get("nodes", {}).get("sph", {}).get("engine_detail", "")
    m = re.search(r"(\d+) particles", detail)
    metrics = ", ".join("%s %.3g / %g" % (k, v["value"], v["bound"]) for k, v in chk["metrics"].items())
    print("| %s | %s | %s | %s | %s | %s | %.0f |" % (
        name, dx, m.group(1) if m else "", summ.get("steps", ""), metrics,
        "yes" if chk.get("pass") else "**no**", summ.get("wall_time_s", float("nan"))))
PY
