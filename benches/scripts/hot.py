#!/usr/bin/env python3
"""Self time of `perf script` samples (DWARF call graphs) by function, iterator adapters
and closures charged to the nearest ctcal function that called them, and where those
are called from. Usage: perf script -i DATA | benches/scripts/hot.py [TOP]"""
import re
import sys
from collections import Counter

GENERIC = re.compile(r"^(<?core::|<?alloc::|<?rayon|rayon_core|\{closure|call_|catch_unwind|"
                     r"halt_unwinding|do_call|helper|fold|for_each|map_fold|__mem|_int_|malloc|"
                     r"cfree|\[unknown\]|<&F|<F|std::)")


def frames(block):
    out = []
    for line in block[1:]:
        parts = line.strip().split(None, 1)
        if len(parts) == 2:
            sym = re.sub(r"\+0x[0-9a-f]+$", "", parts[1].rsplit(" (", 1)[0])
            out.append(sym)
    return out


def owner(stack):
    for sym in stack:
        if "ctcal" in sym and not GENERIC.match(sym.split("::")[-1]):
            return re.sub(r"<.*?>", "", sym)
    return stack[0] if stack else "?"


def main():
    top = int(sys.argv[1]) if len(sys.argv) > 1 else 25
    blocks, block = [], []
    for line in sys.stdin:
        if line.strip():
            block.append(line)
        elif block:
            blocks.append(block)
            block = []
    if block:
        blocks.append(block)
    leaf, own, caller = Counter(), Counter(), Counter()
    for b in blocks:
        stack = frames(b)
        if not stack:
            continue
        leaf[stack[0]] += 1
        o = owner(stack)
        own[o] += 1
        rest = stack[stack.index(o) + 1:] if o in stack else []
        caller[(o, owner(rest) if rest else "-")] += 1
    n = sum(leaf.values())
    print(f"{n} samples\n\nself time, charged to the nearest ctcal function:")
    for sym, c in own.most_common(top):
        print(f"{100 * c / n:6.2f} %  {sym}")
    print("\n... and its caller:")
    for (sym, up), c in caller.most_common(top):
        print(f"{100 * c / n:6.2f} %  {sym}  <-  {up}")


main()
