"""Runs models/four-bar.toml from Python and plots the rocker's angle and the
motor's multiplier against time (matplotlib, optional: without it, prints a
note and a few numbers instead).

    python python/examples/four_bar.py [model] [--out four-bar.png]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import mstar

ROOT = Path(__file__).resolve().parents[2]


def main() -> None:
    p = argparse.ArgumentParser(description="Run a model and plot it.")
    p.add_argument("model", nargs="?", default=str(ROOT / "models" / "four-bar.toml"))
    p.add_argument("--out", default="four-bar.png", help="the figure (PNG)")
    args = p.parse_args()

    model = mstar.load(args.model)
    print(model.check()["report"], end="")
    result = model.run()
    s = result.stats
    print(f"{s.steps} steps, {s.newton_iterations} Newton iterations, "
          f"{s.factorizations} factorizations, {s.wall_time:.3f} s")

    coord = "rocker.theta" if "rocker.theta" in result.coords else result.coords[-1]
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("note: matplotlib is not installed (pip install matplotlib): no plot; "
              f"{coord} at the end: {result[coord][-1]:.6f}")
        return
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
    top.plot(result.t, result[coord])
    top.set_ylabel(coord)
    bottom.plot(result.t, result.lam[:, -1])
    bottom.set_ylabel(f"λ ({result.constraints[-1]})")
    bottom.set_xlabel("t, s")
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
