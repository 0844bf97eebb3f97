#!/usr/bin/env python3
"""Check that the declared minimum Rust version (`rust-version` of every workspace member) is
at least the highest `rust-version` among the locked dependencies (Cargo.lock), so that
`cargo install --locked` works on the version we declare.

Only one toolchain can be installed on the CI machine, so the code itself cannot be compiled
with the declared version; clippy's `incompatible_msrv` lint (on by default, `-D warnings` in
CI) reads the same `rust-version` and rejects standard-library APIs stabilised after it.

Run: `python3 scripts/check-msrv.py` (exit 1 and the offending packages when the declaration
is too low). `--self-test` checks that the comparison can fail (a negative control).
"""

import json
import subprocess
import sys


def version(text):
    """'1.89' or '1.89.0' -> (1, 89, 0)."""
    parts = [int(x) for x in text.split(".")]
    return tuple(parts + [0] * (3 - len(parts)))


def too_low(declared, dependencies):
    """The dependencies whose rust-version exceeds `declared`: [(name, version, needs)]."""
    return [(n, v, r) for n, v, r in dependencies if version(r) > version(declared)]


def main():
    if "--self-test" in sys.argv:
        deps = [("a", "1.0.0", "1.85"), ("b", "0.3.2", "1.89.0")]
        assert too_low("1.89", deps) == [], "1.89 covers 1.89.0"
        assert too_low("1.85", deps) == [("b", "0.3.2", "1.89.0")], "1.85 must fail"
        print("check-msrv self-test: ok")
        return 0
    meta = json.loads(
        subprocess.run(
            ["cargo", "metadata", "--format-version", "1", "--locked"],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
    )
    members = set(meta["workspace_members"])
    declared = {}
    dependencies = []
    for p in meta["packages"]:
        if p["id"] in members:
            declared[p["name"]] = p.get("rust_version")
        elif p.get("rust_version"):
            dependencies.append((p["name"], p["version"], p["rust_version"]))
    failed = False
    needed = max((version(r) for _, _, r in dependencies), default=(0, 0, 0))
    for name, msrv in sorted(declared.items()):
        if msrv is None:
            print(f"{name}: no rust-version declared")
            failed = True
            continue
        bad = too_low(msrv, dependencies)
        for dep, v, r in bad:
            print(f"{name} declares rust-version {msrv}, but {dep} {v} needs {r}")
        failed |= bool(bad)
    if failed:
        return 1
    print(
        "rust-version "
        + ", ".join(f"{n} {m}" for n, m in sorted(declared.items()))
        + f": covers every locked dependency (highest needs {'.'.join(map(str, needed))})"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
