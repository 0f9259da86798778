#!/usr/bin/env python3
"""Where one function's instructions go, per query: the basic blocks that cost the most.

Usage: callgrind-blocks.py BINARY FUNCTION QUERIES [CALLGRIND_OUT]   (default cg.out)
       callgrind-blocks.py --jit DIR QUERIES [CALLGRIND_OUT]

Reads a `valgrind --tool=callgrind --dump-instr=yes` profile, keeps the instruction counts of
FUNCTION, splits its `objdump -d` disassembly into basic blocks (at jump targets and after
jumps) and prints the twelve (TOP) blocks with the largest cost per query: start address, number of
instructions, how often the block ran per query, and its cost per query. Used by
scripts/count-instructions.sh (BLOCKS=1). EVENT=Bcm ranks the blocks by mispredicted
conditional branches instead (a profile made with --branch-sim=yes; count-instructions.sh
BRANCHES=1).

With --jit, the code is the Cranelift JIT's, dumped to DIR by `SCION_CLIF_DUMP=DIR` (each
function's bytes in NAME.bin and its address in the profiled process in NAME.addr): the costs
are those of every profiled instruction inside each function's bytes, whatever callgrind named
it, and the blocks are ranked across all of them (count-instructions.sh with BACKEND=jit).
"""
import os
import re
import subprocess
import sys


def counts(path, function, event="Ir"):
    """Instruction address -> count of `event` (executions for `Ir`; `Bcm`, mispredicted
    conditional branches, in a profile made with --branch-sim=yes), for `function`."""
    costs, names, inside, addr, column, call = {}, {}, False, 0, 0, False
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
                inside = function is None or names.get(m.group(2), "") == function
            continue
        if line.startswith("calls="):
            # The next line is the call's position and its inclusive cost (the callee's):
            # its position counts for the relative addresses after it, its cost does not.
            call = True
            continue
        if not line or not (line[0].isdigit() or line[0] in "+-*"):
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
        if call:
            call = False
            continue
        if inside and len(parts) >= 3:
            value = int(parts[2 + column]) if len(parts) > 2 + column else 0
            costs[addr] = costs.get(addr, 0) + value
    return costs


def disassembly(command):
    """(address, instruction) of each line of an objdump disassembly."""
    out = subprocess.run(command, capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        m = re.match(r"\s*([0-9a-f]+):\s*(.*)", line)
        if m and not m.group(2).startswith("(bad)"):
            yield int(m.group(1), 16), m.group(2)


def jit_code(directory):
    """(function, address, instruction) of every function the Cranelift JIT dumped."""
    for name in sorted(os.listdir(directory)):
        if not name.endswith(".addr") or not os.path.exists(os.path.join(directory, name[:-5] + ".bin")):
            continue
        function = name[:-5]
        base = int(open(os.path.join(directory, name)).read().strip(), 16)
        for a, ins in disassembly(["objdump", "-D", "-b", "binary", "-m", "i386:x86-64",
                                   "--no-show-raw-insn", f"--adjust-vma={base:#x}",
                                   os.path.join(directory, function + ".bin")]):
            yield function, a, ins


def main():
    event = os.environ.get("EVENT", "Ir")
    if sys.argv[1] == "--jit":
        queries = int(sys.argv[3])
        costs = counts(sys.argv[4] if len(sys.argv) > 4 else "cg.out", None, event)
        code = list(jit_code(sys.argv[2]))
        function = "the JIT's code"
    else:
        binary, function, queries = sys.argv[1], sys.argv[2], int(sys.argv[3])
        costs = counts(sys.argv[4] if len(sys.argv) > 4 else "cg.out", function, event)
        code = [(function, a, ins) for a, ins in disassembly(
            ["objdump", "-d", "--no-show-raw-insn", binary, "--disassemble=" + function])]
    rows, targets = [], set()
    for f, a, ins in code:
        rows.append((a, costs.get(a, 0) / queries, ins, f))
        t = re.search(r"\s(?:0x)?([0-9a-f]+)(?: <|$)", ins)
        if ins.startswith("j") and t:
            targets.add(int(t.group(1), 16))
    blocks = []
    for i, (a, c, ins, f) in enumerate(rows):
        if not blocks or a in targets or rows[i - 1][2].startswith(("j", "ret")) or rows[i - 1][3] != f:
            blocks.append([a, 0, 0.0, c, ins if function == f else f"{f}: {ins}"])
        blocks[-1][1] += 1
        blocks[-1][2] += c
    what = "instructions" if event == "Ir" else event
    print(f"{function}: {sum(r[1] for r in rows):.1f} {what} per query")
    print(f"block     instrs  {'runs/query' if event == 'Ir' else event + '@first':>10}  {what[:6]}/query  first instruction")
    for a, n, cost, runs, first in sorted(blocks, key=lambda b: -b[2])[:int(os.environ.get("TOP", "12"))]:
        print(f"{a:8x}  {n:6d}  {runs:10.2f}  {cost:12.1f}  {first[:64]}")


if __name__ == "__main__":
    main()
