#!/usr/bin/env python3
"""Compare two outputs of `examples/record_maps/` (the "same maps" regression check).

Usage: scripts/compare-maps.py BASE.txt CURRENT.txt [--tol 1e-14] [--verbose]

Each line of a recording is `CASE_ID ok TOKENS…` or `CASE_ID error MESSAGE`. A token is
`name[index]=value|bits` (a float: `{:e}` with 17 significant digits and its IEEE-754 bits in
hex) or `name=text` (compared as text). Floats are compared by their bits: equal bits are
"bit-identical"; otherwise the relative difference is |a − b| / max(|a|, s), where a is the base
value and s the largest |value| of the same vector (`name`) in the base's case, so that
components near zero of a vector are measured against the vector's size.

Prints a summary: cases bit-identical, cases within the tolerance (not bit-identical), cases
beyond it with their worst difference, and cases whose status (ok/error), text tokens or set
of values differ, or which occur in only one file. Exits 1 if any case is beyond the
tolerance, changed status, changed a text token or a set of values, or is missing; 0
otherwise. A changed error message (both runs failing) is reported but not a failure.
"""

import argparse
import math
import struct
import sys


def parse(path):
    """Case id -> (status, payload); payload: dict of tokens (ok) or the message (error)."""
    cases = {}
    order = []
    with open(path, encoding="utf-8") as f:
        for lineno, line in enumerate(f, 1):
            line = line.rstrip("\n")
            if not line.strip():
                continue
            parts = line.split(" ", 2)
            if len(parts) < 2 or parts[1] not in ("ok", "error"):
                sys.exit(f"{path}:{lineno}: not a record_maps line: {line[:120]!r}")
            case, status = parts[0], parts[1]
            rest = parts[2] if len(parts) > 2 else ""
            if case in cases:
                sys.exit(f"{path}:{lineno}: case {case} recorded twice")
            if status == "ok":
                tokens = {}
                for tok in rest.split():
                    key, sep, value = tok.partition("=")
                    if not sep:
                        sys.exit(f"{path}:{lineno}: bad token {tok!r}")
                    if "|" in value:
                        text, bits = value.split("|", 1)
                        x = struct.unpack("<d", int(bits, 16).to_bytes(8, "little"))[0]
                        tokens[key] = ("f", int(bits, 16), x, text)
                    else:
                        tokens[key] = ("t", value)
                cases[case] = ("ok", tokens)
            else:
                cases[case] = ("error", rest)
            order.append(case)
    return cases, order


def vector_name(key):
    return key.split("[", 1)[0]


def compare_ok(base, cur):
    """(worst relative difference, its key, problems) over the tokens of one case."""
    problems = []
    if set(base) != set(cur):
        only_b = sorted(set(base) - set(cur))
        only_c = sorted(set(cur) - set(base))
        problems.append(
            f"values differ: only in base {only_b[:5]}, only in current {only_c[:5]}"
        )
    scale = {}
    for key, tok in base.items():
        if tok[0] == "f" and math.isfinite(tok[2]):
            name = vector_name(key)
            scale[name] = max(scale.get(name, 0.0), abs(tok[2]))
    worst, worst_key = 0.0, None
    for key, tb in base.items():
        tc = cur.get(key)
        if tc is None:
            continue
        if tb[0] != tc[0]:
            problems.append(f"{key}: a number in one run, text in the other")
            continue
        if tb[0] == "t":
            if tb[1] != tc[1]:
                problems.append(f"{key}: {tb[1]!r} -> {tc[1]!r}")
            continue
        if tb[1] == tc[1]:
            continue
        a, b = tb[2], tc[2]
        if math.isfinite(a) and math.isfinite(b):
            denom = max(abs(a), scale.get(vector_name(key), 0.0))
            rel = abs(a - b) / denom if denom > 0 else math.inf
            if rel == 0.0:
                rel = 5e-324  # e.g. +0 and -0: not bit-identical, but no difference
        else:
            rel = math.inf
        if rel > worst:
            worst, worst_key = rel, key
    return worst, worst_key, problems


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("base")
    ap.add_argument("current")
    ap.add_argument("--tol", type=float, default=1e-14, help="relative tolerance (1e-14)")
    ap.add_argument(
        "--verbose", action="store_true", help="list every case that is not bit-identical"
    )
    args = ap.parse_args()
    base, order = parse(args.base)
    cur, cur_order = parse(args.current)

    identical, within, beyond, broken, message_changed = [], [], [], [], []
    for case in order:
        if case not in cur:
            broken.append((case, "missing in current"))
            continue
        (sb, pb), (sc, pc) = base[case], cur[case]
        if sb != sc:
            detail = pc if sc == "error" else pb
            why = f"status {sb} -> {sc}"
            if isinstance(detail, str):
                why += f": {detail[:200]}"
            broken.append((case, why))
            continue
        if sb == "error":
            identical.append(case)
            if pb != pc:
                message_changed.append((case, pb, pc))
            continue
        worst, key, problems = compare_ok(pb, pc)
        if problems:
            broken.append((case, "; ".join(problems)))
        elif worst == 0.0:
            identical.append(case)
        elif worst <= args.tol:
            within.append((case, worst, key))
        else:
            beyond.append((case, worst, key))
    for case in cur_order:
        if case not in base:
            broken.append((case, "missing in base"))

    total = len(order) + sum(1 for c in cur_order if c not in base)
    print(f"same maps: {total} cases, {args.base} vs {args.current}")
    rows = [
        ("bit-identical", len(identical)),
        (f"within {args.tol:.0e} (not bit-identical)", len(within)),
        (f"beyond {args.tol:.0e}", len(beyond)),
        ("status, text or values changed", len(broken)),
    ]
    for label, count in rows:
        print(f"  {label + ':':<40}{count:>5}")
    if args.verbose and within:
        print("cases within the tolerance, not bit-identical (worst relative difference):")
        for case, worst, key in within:
            print(f"  {worst:9.2e}  {case}  ({key})")
    if beyond:
        print(f"cases beyond {args.tol:.0e} (worst relative difference, at):")
        for case, worst, key in sorted(beyond, key=lambda x: -x[1]):
            print(f"  {worst:9.2e}  {case}  ({key})")
    if broken:
        print("cases whose status, text or set of values changed:")
        for case, why in broken:
            print(f"  {case}: {why}")
    if message_changed:
        print("error messages changed (both runs fail; not a failure):")
        for case, a, b in message_changed:
            print(f"  {case}:\n    base:    {a[:200]}\n    current: {b[:200]}")
    ok = not beyond and not broken
    print("SAME MAPS" if ok else "MAPS DIFFER")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
