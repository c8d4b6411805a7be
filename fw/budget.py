#!/usr/bin/env python3
"""Checks measured figures against fw/budgets.txt.

Usage: budget.py BUDGETS MEASURES [REPORT.md]
MEASURES holds `<key> <value>` lines (integers). Prints a table of every budget with its
measured value; writes it as Markdown to REPORT.md when given. Exit status 1 when a budget is
broken or its measure is missing, 2 on a malformed budget file.
"""

import re
import sys

LINE = re.compile(r"^(\w+)\s*(<=|>=)\s*(-?\d+)$")


def main():
    if len(sys.argv) not in (3, 4):
        print(__doc__, file=sys.stderr)
        return 2
    measures = {}
    with open(sys.argv[2]) as fh:
        for line in fh:
            parts = line.split()
            if len(parts) == 2 and re.fullmatch(r"-?\d+", parts[1]):
                measures[parts[0]] = int(parts[1])
    rows = []
    failed = 0
    with open(sys.argv[1]) as fh:
        for n, raw in enumerate(fh, 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            m = LINE.match(line)
            if not m:
                print(f"{sys.argv[1]}:{n}: cannot parse {raw.strip()!r}", file=sys.stderr)
                return 2
            key, op, limit = m.group(1), m.group(2), int(m.group(3))
            value = measures.get(key)
            if value is None:
                ok, shown = False, "missing"
            else:
                ok = value <= limit if op == "<=" else value >= limit
                shown = str(value)
            failed += not ok
            rows.append((key, shown, f"{op} {limit}", "ok" if ok else "BROKEN"))
    width = max(len(r[0]) for r in rows)
    for key, shown, limit, status in rows:
        print(f"  {key:<{width}}  {shown:>9}  {limit:>10}  {status}")
    if len(sys.argv) == 4:
        with open(sys.argv[3], "w") as fh:
            fh.write("| measure | value | budget | |\n| --- | ---: | ---: | --- |\n")
            for key, shown, limit, status in rows:
                fh.write(f"| `{key}` | {shown} | {limit} | {status} |\n")
    print(f"budget: {len(rows) - failed} of {len(rows)} within budget"
          + (f", {failed} BROKEN" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
