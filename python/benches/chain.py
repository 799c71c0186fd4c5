"""Stepping time of a chain of N slender bars from Python against `mstar run`
on the same model file (docs/python.md, "Cost"): the runs are the same bit
for bit, so the difference is what the binding adds per step (copying the
state into its arrays, polling for Ctrl-C).

    python python/benches/chain.py [--links 10000] [--t-end 0.1] [--cli target/release/mstar] [--repeat 3]

Prints the CLI's `wall time` (its stepping time, from the initial state on)
and Result.stats.wall_time (the same span), best of --repeat runs each.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mstar

ROOT = Path(__file__).resolve().parents[2]


def chain_toml(n: int, t_end: float) -> str:
    """n 1 m bars of 1 kg hinged end to end, the first to the ground,
    released horizontally; tol 1e-8 and rho 0.8 as README's `mstar chain`."""
    parts = ['format = "mstar.planar/1"\n']
    for i in range(n):
        parts.append(
            f'[[body]]\nname = "bar{i}"\nmass = 1.0\ninertia = 0.08333333333333333\n'
            f"pose = [{i + 0.5}, 0.0, 0.0]\n"
        )
    for i in range(n):
        a = '"ground"' if i == 0 else f'"bar{i - 1}"'
        pa = "[0.0, 0.0]" if i == 0 else "[0.5, 0.0]"
        parts.append(
            f'[[joint]]\nname = "hinge{i}"\ntype = "revolute"\nbodies = [{a}, "bar{i}"]\n'
            f"points = [{pa}, [-0.5, 0.0]]\n"
        )
    parts.append(f"[simulation]\nt_end = {t_end!r}\nh = 1e-3\ntol = 1e-8\nrho = 0.8\n")
    return "\n".join(parts)


def cli_wall(cli: str, model: Path) -> float:
    out = subprocess.run([cli, "run", str(model)], capture_output=True, text=True, check=False)
    match = re.search(r"wall time: ([0-9.]+) s", out.stdout)
    if match is None:
        sys.exit(f"{cli} run {model}: no wall time in its output:\n{out.stdout}{out.stderr}")
    return float(match.group(1))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--links", type=int, default=10_000)
    p.add_argument("--t-end", type=float, default=0.1)
    p.add_argument("--cli", default=str(ROOT / "target" / "release" / "mstar"))
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        model = Path(tmp) / "chain.toml"
        model.write_text(chain_toml(args.links, args.t_end))
        loaded = mstar.load(model)
        cli, py, total = [], [], []
        for _ in range(args.repeat):
            cli.append(cli_wall(args.cli, model))
            start = time.perf_counter()
            result = loaded.run()
            total.append(time.perf_counter() - start)
            py.append(result.stats.wall_time)
    steps = result.stats.steps
    c, s = min(cli), min(py)
    print(f"{args.links}-bar chain, {steps} steps of 1e-3 s, best of {args.repeat}:")
    print(f"  mstar run (stepping):     {c:.3f} s  ({c / steps * 1e3:.2f} ms per step)")
    print(f"  Python (stepping):        {s:.3f} s  ({s / steps * 1e3:.2f} ms per step)  {100 * (s / c - 1):+.1f} %")
    print(f"  Python (whole Model.run): {min(total):.3f} s  (start-up and arrays included)")


if __name__ == "__main__":
    main()
