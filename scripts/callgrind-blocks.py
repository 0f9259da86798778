#!/usr/bin/env python3
"""Where one function's instructions go, per query: the basic blocks that cost the most.

Usage: callgrind-blocks.py BINARY FUNCTION QUERIES [CALLGRIND_OUT]   (default cg.out)

Reads a `valgrind --tool=callgrind --dump-instr=yes` profile, keeps the instruction counts of
FUNCTION, splits its `objdump -d` disassembly into basic blocks (at jump targets and after
jumps) and prints the twelve (TOP) blocks with the largest cost per query: start address, number of
instructions, how often the block ran per query, and its cost per query. Used by
scripts/count-instructions.sh (BLOCKS=1). EVENT=Bcm ranks the blocks by mispredicted
conditional branches instead (a profile made with --branch-sim=yes; count-instructions.sh
BRANCHES=1).
"""
import os
import re
import subprocess
import sys


def counts(path, function, event="Ir"):
    """Instruction address -> count of `event` (executions for `Ir`; `Bcm`, mispredicted
    conditional branches, in a profile made with --branch-sim=yes), for `function`."""
    costs, names, inside, addr, column = {}, {}, False, 0, 0
    for line in open(path):
        line = line.rstrip("\n")
        if line.startswith("events:"):
            events = line.split()[1:]
            if event not in events:
                sys.exit(f"callgrind-blocks: the profile has no event {event} ({' '.join(events)})")
            column = events.index(event)
            continue
        m = re.match(r"(c?fn)=\((\d+)\)(?: (.*))?", line)
        if m:
            if m.group(3):
                names[m.group(2)] = m.group(3)
            if m.group(1) == "fn":
                inside = names.get(m.group(2), "") == function
            continue
        if line.startswith("calls=") or not line or not (line[0].isdigit() or line[0] in "+-*"):
            continue
        parts = line.split()
        a = parts[0]
        if a.startswith("0x"):
            addr = int(a, 16)
        elif a.startswith("+"):
            addr += int(a[1:])
        elif a.startswith("-"):
            addr -= int(a[1:])
        # `positions: instr line`: address, line, then the costs (trailing zeros left out).
        if inside and len(parts) >= 3:
            value = int(parts[2 + column]) if len(parts) > 2 + column else 0
            costs[addr] = costs.get(addr, 0) + value
    return costs


def main():
    binary, function, queries = sys.argv[1], sys.argv[2], int(sys.argv[3])
    event = os.environ.get("EVENT", "Ir")
    costs = counts(sys.argv[4] if len(sys.argv) > 4 else "cg.out", function, event)
    dis = subprocess.run(
        ["objdump", "-d", "--no-show-raw-insn", binary, "--disassemble=" + function],
        capture_output=True, text=True, check=True).stdout
    rows, targets = [], set()
    for line in dis.splitlines():
        m = re.match(r"\s*([0-9a-f]+):\s*(.*)", line)
        if not m:
            continue
        a, ins = int(m.group(1), 16), m.group(2)
        rows.append((a, costs.get(a, 0) / queries, ins))
        t = re.search(r"\s([0-9a-f]+) <", ins)
        if ins.startswith("j") and t:
            targets.add(int(t.group(1), 16))
    blocks = []
    for i, (a, c, ins) in enumerate(rows):
        if not blocks or a in targets or rows[i - 1][2].startswith(("j", "ret")):
            blocks.append([a, 0, 0.0, c, ins])
        blocks[-1][1] += 1
        blocks[-1][2] += c
    what = "instructions" if event == "Ir" else event
    print(f"{function}: {sum(r[1] for r in rows):.1f} {what} per query")
    print(f"block     instrs  {'runs/query' if event == 'Ir' else event + '@first':>10}  {what[:6]}/query  first instruction")
    for a, n, cost, runs, first in sorted(blocks, key=lambda b: -b[2])[:int(os.environ.get("TOP", "12"))]:
        print(f"{a:8x}  {n:6d}  {runs:10.2f}  {cost:12.1f}  {first[:48]}")


if __name__ == "__main__":
    main()
