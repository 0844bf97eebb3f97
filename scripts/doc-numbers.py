#!/usr/bin/env python3
"""Docs that cannot drift silently: every number README.md and the guide quote from a command.

    python3 scripts/doc-numbers.py              # run every command, rewrite the quotes
    python3 scripts/doc-numbers.py --check      # run every command, fail on any drift
    python3 scripts/doc-numbers.py --self-test  # negative controls: corrupted copies must fail

Each entry of QUOTES below names a file, where in it the quote is (a fenced block after an
anchor, or a number matched by a pattern) and the command that prints it. `gvi` in a command is
the release binary (target/release/gvi, or $GVI); commands run in a scratch directory.

Deterministic numbers are compared at the digits the document prints (4.409e-6 matches any
4.4085e-6…4.4095e-6); wall-clock numbers (`0.011 s`, `members/s`, speed-ups) are normalised
away in --check and rewritten only when a deterministic number changed or with --timings.
The script also checks that:

- docs/figures/kepler-orbit.svg is the chart the README's main command draws (byte for byte);
- the README's quickstart block is examples/quickstart.rs verbatim;
- every `gvi …` line of the README's ```sh blocks runs as written (exit status 0).

Numbers quoted from slow studies (work–precision, benches, 15-minute scripts) are not covered;
SLOW lists the ones known, with their commands (printed by --list-slow).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional

ROOT = Path(__file__).resolve().parent.parent
README_LIMIT = 12_000  # bytes

# A wall-clock quantity: a number followed by a time unit or a rate, and speed-ups.
TIMING = [
    r"\d+(?:\.\d+)?(?:e-?\d+)? (?:s|ms|µs)\b",
    r"\d+(?:\.\d+)? members/s",
    r"speed-up \d+(?:\.\d+)?×",
]


@dataclass
class Block:
    """A fenced block after `anchor` in `file`: the output of `cmd` (stdout, stderr or both)."""

    file: str
    anchor: str
    cmd: str
    stream: str = "stderr"
    drop: list = field(default_factory=list)  # regexes of output lines left out of the quote
    prefix: str = ""  # text kept in front of the output (e.g. "$ gvi run …\n")


@dataclass
class Number:
    """A number in `file`: group 1 of `doc` (a regex); its value: group 1 of `out` in the
    command's output, or `value(output, workdir)`."""

    file: str
    doc: str
    cmd: str
    out: str = ""
    value: Optional[Callable[[str, Path], float]] = None
    stream: str = "stderr"


MAIN = "gvi run kepler --output out/kepler.csv --plot out/kepler-orbit.svg"
# Commands quoted as the README lists them share one run with the README's command check.
REPRODUCE = "gvi reproduce"
REFINE_TEST = "gvi refine kepler --vary n --range 8:44:2"
REFINE_16 = "gvi refine kepler --vary n --range 16:48:2 --out out/refine-16"
REFINE_GUIDE = "gvi refine kepler --vary n --range 6:44:2 --out out/refine-6"
FIGURE_EIGHT = "gvi periodic figure-eight"
NBODY = {n: f"gvi nbody-report solar-system --n {n} --out out/nbody-{n}" for n in (15, 25, 32)}
NBODY[25] = "gvi nbody-report solar-system"
DAMPED = "gvi run damped-oscillator --output out/damped.csv"


def reproduce_k(row: str) -> Callable[[str, Path], float]:
    """The fitted K of a row of `gvi reproduce`'s summary table."""

    def get(out: str, _wd: Path) -> float:
        m = re.search(r"\| " + re.escape(row) + r" \| [^|]* \| K ([0-9.]+) \|", out)
        if not m:
            raise ValueError(f"no row {row!r} in the output")
        return float(m.group(1))

    return get


def fit_field(which: str, key: str) -> Callable[[str, Path], float]:
    """From `gvi refine`'s stderr: the rate (`rate`) or window start/end (`lo`, `hi`) of the
    fit on `which` line (`one-step map` or `Galerkin curves`)."""

    def get(out: str, _wd: Path) -> float:
        m = re.search(
            re.escape(which) + r": error ≈ \S+·([0-9.]+)ⁿ over n ∈ \[(\d+), (\d+)\]", out
        )
        if not m:
            raise ValueError(f"no {which} fit in the output")
        return float(m.group({"rate": 1, "lo": 2, "hi": 3}[key]))

    return get


def csv_field(path: str, basis: str, quadrature: str, n: int, column: str) -> Callable[[str, Path], float]:
    """A column of the row (basis, quadrature, n) of a study's CSV, in the scratch directory."""

    def get(_out: str, wd: Path) -> float:
        import csv

        with open(wd / path, newline="") as f:
            for row in csv.DictReader(f):
                if (row["basis"], row["quadrature"], row["n"]) == (basis, quadrature, str(n)):
                    return float(row[column])
        raise ValueError(f"no row {basis}, {quadrature}, n = {n} in {path}")

    return get


COMPARE_BASES = "gvi compare-bases kepler --range 4:64:4"
SPRING = "gvi run spring-pendulum --output out/spring-pendulum.csv"
FPU2 = "gvi run fpu-two-frequency --output out/fpu-two-frequency.csv"
BASES_CSV = "out/compare-bases/compare-bases.csv"

QUOTES: list = [
    # README: the main command's summary (its first two lines go to stderr too).
    Block(
        "README.md",
        "The first command prints",
        MAIN,
        drop=[r"^created directory "],
    ),
    # Ensembles: the summary of the guide's run (the throughput line's times are normalised).
    Block(
        "docs/guide/ensembles.md",
        "It prints (on this 2-core machine;",
        "gvi ensemble double-pendulum --count 64 --perturb 1e-6 --seed 1 --throughput-sample 32"
        " --output out/dp.csv",
        stream="both",
        drop=[r"^created directory "],
    ),
    # README: the fitted Kepler rate and where it comes from.
    Number("README.md", r"one-step map error\s+O\(([0-9.]+)ⁿ\)", REPRODUCE,
           value=reproduce_k("Kepler one-step map")),
    Number("README.md", r"other fit windows give\s+([0-9.]+)–", REFINE_TEST,
           value=fit_field("one-step map", "rate")),
    Number("README.md", r"other fit windows give\s+[0-9.]+–([0-9.]+)", REFINE_16,
           value=fit_field("one-step map", "rate")),
    Number("README.md", r"period within ([0-9.e-]+) of Simó", FIGURE_EIGHT,
           out=r"reference [0-9.]+, difference ([0-9.e-]+)\)"),
    Number("README.md", r"Mercury within ([0-9.e-]+) AU at n = 25", NBODY[25], out=r"Mercury\s+([0-9.e-]+)",
           stream="both"),
    Number("README.md", r"energy balance to ([0-9.e-]+) \(`gvi run damped-oscillator", DAMPED,
           out=r"energy balance [^:]*: max ([0-9.e-]+),"),
    # Reproducing the paper: the rates of the three commands and their windows.
    Number("docs/guide/reproducing-the-paper.md", r"\*\*O\(([0-9.]+)ⁿ\)\*\*, fitted over n = 16",
           REPRODUCE, value=reproduce_k("Kepler one-step map")),
    Number("docs/guide/reproducing-the-paper.md", r"\*\*O\(([0-9.]+)ⁿ\)\*\*, fitted over n = 34",
           REPRODUCE, value=reproduce_k("Kepler Galerkin curves (large n)")),
    Number("docs/guide/reproducing-the-paper.md", r"`gvi refine kepler --vary n --range 8:44:2` fits ([0-9.]+)",
           REFINE_TEST, value=fit_field("one-step map", "rate")),
    Number("docs/guide/reproducing-the-paper.md", r"--range 8:44:2` fits [0-9.]+ over n = (\d+)",
           REFINE_TEST, value=fit_field("one-step map", "lo")),
    Number("docs/guide/reproducing-the-paper.md", r"--range 16:48:2` fits ([0-9.]+)", REFINE_16,
           value=fit_field("one-step map", "rate")),
    Number("docs/guide/reproducing-the-paper.md", r"--range 16:48:2` fits [0-9.]+ over n = (\d+)", REFINE_16,
           value=fit_field("one-step map", "lo")),
    Number("docs/guide/reproducing-the-paper.md", r"--range 6:44:2` fits ([0-9.]+)", REFINE_GUIDE,
           value=fit_field("one-step map", "rate")),
    Number("docs/guide/reproducing-the-paper.md", r"--range 6:44:2` fits [0-9.]+ over n = (\d+)", REFINE_GUIDE,
           value=fit_field("one-step map", "lo")),
    # Studies: `gvi refine`'s two fit lines, quoted whole.
    Number("docs/guide/studies.md", r"one-step map: error ≈ \S+·([0-9.]+)ⁿ over n ∈ \[12", REFINE_GUIDE,
           value=fit_field("one-step map", "rate")),
    Number("docs/guide/studies.md", r"Galerkin curves: error ≈ \S+·([0-9.]+)ⁿ over n ∈ \[10", REFINE_GUIDE,
           value=fit_field("Galerkin curves", "rate")),
    Number("docs/guide/studies.md", r"one-step map: error ≈ ([0-9.]+)e3·", REFINE_GUIDE,
           out=r"one-step map: error ≈ ([0-9.]+)e3·"),
    Number("docs/guide/studies.md", r"Galerkin curves: error ≈ ([0-9.]+)e3·", REFINE_GUIDE,
           out=r"Galerkin curves: error ≈ ([0-9.]+)e3·"),
    Number("docs/guide/studies.md", r"round-off floor ≈ ([0-9.e-]+)\)`", REFINE_GUIDE,
           out=r"round-off floor ≈ ([0-9.e-]+)\)"),
    # Time transformations: the summaries of `gvi run kepler-e099` and `gvi run pythagorean`
    # (about 1 s and 20 s); the chart path differs from the guide's command, the summary not.
    Block("docs/guide/time-transformations.md", "`gvi run kepler-e099 --output e099.csv` prints",
          "gvi run kepler-e099 --output e099.csv"),
    Block("docs/guide/time-transformations.md", "prints (release binary",
          "gvi run pythagorean --output pythagorean.csv --plot out/pythagorean-steps.svg",
          drop=[r"^created directory ", r"^chart written to "]),
    # Bases and quadratures: the three polynomial bases' map error at n = 64, the kinetic
    # condition numbers, and the README's summary of them.
    *[
        Number("docs/guide/bases-and-quadratures.md", rf"([0-9.e-]+) \({name}\)", COMPARE_BASES,
               value=csv_field(BASES_CSV, name.lower(), "gauss-legendre", 64, "map_error"))
        for name in ("Chebyshev", "Legendre", "Hermite")
    ],
    Number("docs/guide/bases-and-quadratures.md", r"~n³ for Chebyshev \(([0-9.e]+) at n = 64\)", COMPARE_BASES,
           value=csv_field(BASES_CSV, "chebyshev", "gauss-legendre", 64, "kinetic_condition")),
    Number("docs/guide/bases-and-quadratures.md", r"~n⁶ for Hermite\s+\(([0-9.e]+)\)", COMPARE_BASES,
           value=csv_field(BASES_CSV, "hermite", "gauss-legendre", 64, "kinetic_condition")),
    Number("README.md", r"same map, down to ~([0-9.e-]+) at n = 64", COMPARE_BASES,
           value=csv_field(BASES_CSV, "chebyshev", "gauss-legendre", 64, "map_error")),
    # Lie groups: the free rigid body's error.
    Number("docs/guide/lie-group.md", r"n = 16: error ([0-9.e-]+)", "gvi run rigid-body --output out/rb.csv",
           out=r"max position error at step ends: ([0-9.e-]+)"),
    # Forces: the damped oscillator's errors and energy balance.
    Number("docs/guide/forcing.md", r"\(([0-9.e-]+) at the step ends", DAMPED, out=r"at step ends: ([0-9.e-]+)"),
    Number("docs/guide/forcing.md", r"([0-9.e-]+) along the curves at n = 10", DAMPED,
           out=r"along the Galerkin curves: ([0-9.e-]+)"),
    Number("docs/guide/forcing.md", r"∫∂L/∂t\): max ([0-9.e-]+), with", DAMPED, out=r"∫∂L/∂t\): max ([0-9.e-]+),"),
    Number("docs/guide/forcing.md", r"∫∂L/∂t\): max [0-9.e-]+, with E changing by up to\s+([0-9.e-]+)`", DAMPED,
           out=r"with E changing by up to ([0-9.e-]+)"),
    # N-body: the per-body table (n = 15, 25, 32) and the energy errors.
    *[
        Number("docs/guide/nbody.md", rf"(?m)^\| {body} \| " + r"[^|]+ \| " * col + r"([0-9.e-]+) \|", NBODY[n],
               out=rf"{body.replace('–', '-')}\s+([0-9.e-]+)", stream="both")
        for body in ("Mercury", "Venus", "Earth–Moon", "Jupiter", "Pluto")
        for col, n in enumerate((15, 25, 32))
    ],
    Number("docs/guide/nbody.md", r"the reference is (\d+)″ at n = 25", NBODY[25], out=r"\(([0-9.]+) arcsec\)",
           stream="both"),
    Number("docs/guide/nbody.md", r"and ([0-9.]+)″\s+at n = 32", NBODY[32], out=r"\(([0-9.]+) arcsec\)",
           stream="both"),
    *[
        Number("docs/guide/nbody.md", r"Relative energy error " + r"[0-9.e-]+ / " * col + r"([0-9.e-]+)", NBODY[n],
               out=r"(?m)^  energy\s+([0-9.e-]+)", stream="both")
        for col, n in enumerate((15, 25, 32))
    ],
]

# Enriched bases: the runs of the multiscale scenes (each well under a second).
QUOTES += [
    Number("docs/guide/enriched-bases.md", r"`gvi run spring-pendulum` keeps the energy to ([0-9.e-]+)",
           SPRING, out=r"max energy error: ([0-9.e-]+)"),
    Number("docs/guide/enriched-bases.md", r"oscillatory energy within ([0-9.e-]+) of its initial 1/2",
           SPRING, out=r"max oscillatory_energy error: ([0-9.e-]+)"),
    Number("docs/guide/enriched-bases.md", r"`gvi run fpu-two-frequency` keeps the energy to ([0-9.e-]+)",
           FPU2, out=r"max energy error: ([0-9.e-]+)"),
    Number("docs/guide/enriched-bases.md", r"its total oscillatory energy I within ([0-9.e-]+) of I\(0\) = 2",
           FPU2, out=r"max oscillatory_energy error: ([0-9.e-]+)"),
]

# Quoted from commands too slow for CI (minutes to hours, or benches): regenerate by hand.
SLOW = [
    ("README.md / docs/guide/speed.md", "2.61 linear solves per step", "cargo bench --bench step"),
    ("README.md, peers table", "every ratio", "scripts/work-precision-all.sh (15 minutes)"),
    ("docs/guide/tolerance-driven-n.md", "0.68–0.79×, 0.22–0.27×", "gvi tolerance-study … (see the page)"),
    ("docs/guide/geometric-guarantees.md", "the property-test table", "cargo test --release --test geometry -- --nocapture"),
    ("docs/guide/enriched-bases.md", "two-frequency table, nearly-equal threshold, property-test rows",
     "cargo test --test integration enriched_frequencies:: -- --nocapture; "
     "cargo test -p galerkin-vi --lib basis::enriched -- --nocapture"),
    ("docs/guide/enriched-bases.md", "spring-pendulum tables and charts, two-frequency chart",
     "cargo run --release -p galerkin-vi-lab --example enriched_multiscale"),
    ("docs/guide/reproducing-the-paper.md", "oscillator and h-refinement rows",
     "cargo test --release --test paper_core -- --nocapture"),
]


class Runner:
    """Runs each distinct command once, in one scratch directory."""

    def __init__(self, gvi: Path, workdir: Path):
        self.gvi = gvi
        self.workdir = workdir
        self.cache: dict = {}
        self.seconds: dict = {}

    def argv(self, cmd: str) -> list:
        words = cmd.split()
        if words[0] != "gvi":
            raise ValueError(f"not a gvi command: {cmd}")
        return [str(self.gvi)] + words[1:]

    def run(self, cmd: str):
        if cmd not in self.cache:
            start = time.monotonic()
            p = subprocess.run(self.argv(cmd), cwd=self.workdir, capture_output=True, text=True)
            self.seconds[cmd] = time.monotonic() - start
            self.cache[cmd] = p
        return self.cache[cmd]

    def output(self, cmd: str, stream: str) -> str:
        p = self.run(cmd)
        if p.returncode != 0:
            raise RuntimeError(f"`{cmd}` exited with {p.returncode}:\n{p.stderr}")
        return {"stderr": p.stderr, "stdout": p.stdout, "both": p.stdout + p.stderr}[stream]


def rust_e(value: float, decimals: int) -> str:
    """`value` as Rust's `{:.de}` prints it: 4.409e-6, 1.2e3."""
    m, e = f"{value:.{decimals}e}".split("e")
    return f"{m}e{int(e)}"


def like(token: str, value: float) -> str:
    """`value` printed with the digits and style of `token`."""
    if "e" in token:
        mant = token.split("e")[0]
        decimals = len(mant.split(".")[1]) if "." in mant else 0
        return rust_e(value, decimals)
    if "." in token:
        return f"{value:.{len(token.split('.')[1])}f}"
    return str(round(value))


def normalise(text: str) -> str:
    for pat in TIMING:
        text = re.sub(pat, "<wall clock>", text)
    return text


def find_block(text: str, anchor: str):
    """(start, end) of the body of the first fenced block after `anchor`."""
    i = text.find(anchor)
    if i < 0:
        raise ValueError(f"anchor {anchor!r} not found")
    fence = re.compile(r"^```[a-z]*\n", re.M).search(text, i)
    if not fence:
        raise ValueError(f"no block after {anchor!r}")
    end = text.find("\n```", fence.end() - 1)
    return fence.end(), end + 1


class Docs:
    """The documents under `root`, edited in memory and written back at the end."""

    def __init__(self, root: Path):
        self.root = root
        self.text: dict = {}

    def get(self, name: str) -> str:
        if name not in self.text:
            self.text[name] = (self.root / name).read_text()
        return self.text[name]

    def set(self, name: str, text: str):
        self.text[name] = text

    def save(self):
        for name, text in self.text.items():
            path = self.root / name
            if path.read_text() != text:
                path.write_text(text)
                print(f"rewrote {name}")


def block_quote(q: Block, runner: Runner) -> str:
    lines = runner.output(q.cmd, q.stream).splitlines(keepends=True)
    kept = [l for l in lines if not any(re.search(d, l) for d in q.drop)]
    return q.prefix + "".join(kept)


def process(docs: Docs, runner: Runner, write: bool, timings: bool) -> list:
    """Compare (and with `write`, rewrite) every quote; returns the problems found."""
    problems = []
    for q in QUOTES:
        try:
            text = docs.get(q.file)
            if isinstance(q, Block):
                start, end = find_block(text, q.anchor)
                now = block_quote(q, runner)
                was = text[start:end]
                if normalise(was) != normalise(now):
                    problems.append(f"{q.file}: the block after {q.anchor!r} differs from `{q.cmd}`:\n"
                                    + diff(was, now))
                if write and (normalise(was) != normalise(now) or timings):
                    docs.set(q.file, text[:start] + now + text[end:])
            else:
                ms = list(re.finditer(q.doc, text))
                if len(ms) != 1:
                    problems.append(f"{q.file}: pattern {q.doc!r} matches {len(ms)} times, not once")
                    continue
                m = ms[0]
                out = runner.output(q.cmd, q.stream)
                if q.value is not None:
                    value = q.value(out, runner.workdir)
                else:
                    om = re.search(q.out, out)
                    if not om:
                        raise ValueError(f"{q.out!r} not in the output of `{q.cmd}`:\n{out}")
                    value = float(om.group(1))
                token = m.group(1)
                now = like(token, value)
                if now != token:
                    problems.append(f"{q.file}: {token} (pattern {q.doc!r}) is {now} by `{q.cmd}`")
                    if write:
                        docs.set(q.file, text[: m.start(1)] + now + text[m.end(1):])
        except (ValueError, RuntimeError, OSError) as e:
            problems.append(f"{q.file}: {e}")
    problems += figure(docs.root, runner, write)
    problems += quickstart(docs)
    problems += readme_commands(docs, runner)
    size = len(docs.get("README.md").encode())
    if size > README_LIMIT:
        problems.append(f"README.md: {size} bytes, above the limit of {README_LIMIT}")
    return problems


def diff(was: str, now: str) -> str:
    import difflib

    return "".join(difflib.unified_diff(was.splitlines(True), now.splitlines(True), "document", "command"))


def figure(root: Path, runner: Runner, write: bool) -> list:
    """docs/figures/kepler-orbit.svg against the chart of the README's main command."""
    runner.output(MAIN, "stderr")
    drawn = runner.workdir / "out/kepler-orbit.svg"
    committed = root / "docs/figures/kepler-orbit.svg"
    if committed.read_bytes() == drawn.read_bytes():
        return []
    if write:
        shutil.copyfile(drawn, committed)
        print("rewrote docs/figures/kepler-orbit.svg")
    return [f"docs/figures/kepler-orbit.svg is not the chart `{MAIN}` draws"]


def quickstart(docs: Docs) -> list:
    """The README's ```rust block under "## Quickstart" is examples/quickstart.rs verbatim."""
    start, end = find_block(docs.get("README.md"), "## Quickstart")
    example = docs.get("examples/quickstart.rs")
    if docs.get("README.md")[start:end] == example:
        return []
    return ["README.md: the quickstart block is not examples/quickstart.rs:\n"
            + diff(docs.get("README.md")[start:end], example)]


def readme_commands(docs: Docs, runner: Runner) -> list:
    """Every `gvi …` line of the README's ```sh blocks, run as written."""
    problems = []
    text = docs.get("README.md")
    for block in re.findall(r"^```sh\n(.*?)^```", text, re.M | re.S):
        for line in block.splitlines():
            cmd = line.split("#")[0].strip()
            if not cmd.startswith("gvi "):
                continue
            p = runner.run(cmd)
            if p.returncode != 0:
                problems.append(f"README.md: `{cmd}` exited with {p.returncode}: {p.stderr.strip()[-300:]}")
    return problems


def self_test(runner: Runner) -> list:
    """Negative controls: each corruption of a copy of the documents must be caught."""
    corruptions = [
        ("a digit of the main command's block", "README.md", "max position error at step ends: 4.",
         "max position error at step ends: 5."),
        ("the README's fitted rate", "README.md", "map error\n  O(0.", "map error\n  O(0.9"),
        ("the quickstart", "README.md", "spectral(16, 1.0)", "spectral(17, 1.0)"),
        ("a README command", "README.md", "gvi check kepler --n 12", "gvi check kepler --n 12 --nonsense"),
        ("a guide number", "docs/guide/studies.md", "Galerkin curves: error ≈ 1.", "Galerkin curves: error ≈ 2."),
        ("an enriched-bases number", "docs/guide/enriched-bases.md",
         "`gvi run spring-pendulum` keeps the energy to 5.", "`gvi run spring-pendulum` keeps the energy to 6."),
        ("the figure", "docs/figures/kepler-orbit.svg", "<svg ", "<svg data-x=\"1\" "),
        ("the Kepler e = 0.99 summary", "docs/guide/time-transformations.md",
         "  max position error: ", "  max position error: 9"),
    ]
    failures = []
    files = {q.file for q in QUOTES} | {"examples/quickstart.rs", "docs/figures/kepler-orbit.svg"}
    with tempfile.TemporaryDirectory() as tmp:
        copy = Path(tmp)
        for name in files:
            (copy / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(ROOT / name, copy / name)
        clean = process(Docs(copy), runner, write=False, timings=False)
        if clean:
            failures.append("the uncorrupted copy fails (run --check for details)")
        for what, name, old, new in corruptions:
            original = (copy / name).read_text()
            if old not in original:
                failures.append(f"self-test: {old!r} not in {name}")
                continue
            (copy / name).write_text(original.replace(old, new, 1))
            caught = process(Docs(copy), runner, write=False, timings=False)
            (copy / name).write_text(original)
            status = "caught" if len(caught) > len(clean) else "NOT CAUGHT"
            print(f"self-test: corrupting {what}: {status}")
            if status != "caught":
                failures.append(f"self-test: corrupting {what} was not caught")
    return failures


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="compare only; exit 1 on any drift")
    ap.add_argument("--self-test", action="store_true", help="also run the negative controls")
    ap.add_argument("--timings", action="store_true", help="rewrite wall-clock numbers too")
    ap.add_argument("--list-slow", action="store_true", help="list the quotes of slow commands")
    ap.add_argument("--gvi", default=os.environ.get("GVI", str(ROOT / "target/release/gvi")))
    args = ap.parse_args()
    if args.list_slow:
        for where, what, cmd in SLOW:
            print(f"{where}: {what}: {cmd}")
        return 0
    gvi = Path(args.gvi)
    if not gvi.exists():
        print(f"doc-numbers: no gvi binary at {gvi} (cargo build --release, or --gvi PATH)", file=sys.stderr)
        return 2
    start = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="doc-numbers-") as wd:
        runner = Runner(gvi.resolve(), Path(wd))
        docs = Docs(ROOT)
        problems = process(docs, runner, write=not args.check, timings=args.timings)
        if not args.check:
            docs.save()
            for p in problems:
                print(f"doc-numbers: updating: {p.splitlines()[0]}")
            # What rewriting cannot fix (a failing command, a missing anchor) remains.
            problems = process(Docs(ROOT), runner, write=False, timings=False)
        if args.self_test:
            problems += self_test(runner)
        slowest = sorted(runner.seconds.items(), key=lambda kv: -kv[1])[:3]
    for p in problems:
        print(f"doc-numbers: {p}", file=sys.stderr)
    print(f"doc-numbers: {len(QUOTES)} quotes, {len(runner.cache)} commands, "
          f"{time.monotonic() - start:.1f} s (slowest: "
          + ", ".join(f"`{c}` {s:.1f} s" for c, s in slowest) + ")")
    if problems:
        print("doc-numbers: the documents drifted from their commands; "
              "`python3 scripts/doc-numbers.py` rewrites them", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
