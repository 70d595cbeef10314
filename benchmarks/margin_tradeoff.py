"""What the friction margin buys and costs: effort against released-arm drift (issue 13).

The active law removes the friction the model may overstate from the operator torque, so
that a released arm cannot run away on a model whose friction is too high: the level's
whole relative error (20 % of τ_C after the start-up calibration). This runs the guiding
benchmark's 56 cases (:mod:`leadthrough.experiments.guiding`) with that margin at 1, ¾, ½
and 0 of its default (``guiding_variants``) and draws the median and worst effort (active /
passive) and the worst drift of a released active arm over 10 s against it, with the 1 mrad
goal.

Usage (about 12 min; ``--reuse`` draws from JSONs saved by an earlier run)::

    python benchmarks/margin_tradeoff.py [--seeds 5-8] [--cases quick]
        [--out margin_runs] [--reuse] [--figure docs/bench/margin_tradeoff.png]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import guiding_variants
from guiding_quality import parse_seeds
from leadthrough.experiments.guiding import evaluate
from leadthrough.model import robots

#: (margin as a fraction of the default, the level's whole error; factory name in
#: guiding_variants or None for the default).
VARIANTS = ((1.0, None), (0.75, "three_quarter_friction_margin"),
            (0.5, "half_friction_margin"), (0.0, "no_friction_margin"))  # fmt: skip
#: Where the default sits on the figure's axis, and the axis.
DEFAULT, AXIS = 1.0, "friction margin / the level's whole error (the default)"


def run(fraction: float, name: str | None, kind: str, seeds: list[int], out: Path,
        reuse: bool) -> dict:  # fmt: skip
    """The benchmark's per-case figures with the margin at ``fraction`` (saved in ``out``)."""
    path = out / f"margin_{fraction:g}{'' if kind == 'full' else '_' + kind}.json"
    if reuse and path.exists():
        return json.loads(path.read_text())["cases"]
    factory = None if name is None else getattr(guiding_variants, name)
    start = time.perf_counter()

    def report(case: str, _: dict) -> None:
        print(f"  margin {fraction:g}: {case} ({time.perf_counter() - start:.0f} s)", flush=True)

    results, stats = evaluate(kind, factory, robots.yumi(), report, seeds)
    path.write_text(json.dumps({"cases": results, "summary": stats}, indent=1))
    return results


def draw(rows: list[tuple[float, dict]], figure: Path) -> None:
    """Effort (median, worst) and worst drift against the margin fraction."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fractions = np.array([fraction for fraction, _ in rows])
    effort = [np.array([c["effort"] for c in cases.values()]) for _, cases in rows]
    drift = np.array([max(c["drift"] for c in cases.values()) for _, cases in rows])
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    left.plot(fractions, [np.median(e) for e in effort], "o-", label="median")
    left.plot(fractions, [np.max(e) for e in effort], "s--", label="worst")
    left.axhline(0.5, color="grey", lw=0.8, ls=":", label="goal (median)")
    left.set(xlabel=AXIS, ylabel="RMS hand force, active / passive",
             title="effort while guiding")  # fmt: skip
    right.semilogy(fractions, drift, "o-", color="C3")
    right.axhline(1.0, color="grey", lw=0.8, ls=":", label="goal: < 1 mrad")
    right.set(xlabel=AXIS, ylabel="worst drift over 10 s [mrad]",
              title="released active arm")  # fmt: skip
    for axis in (left, right):
        axis.axvline(DEFAULT, color="k", lw=0.8, alpha=0.4)
        axis.annotate("default", (DEFAULT, axis.get_ylim()[1]), ha="right", va="top",
                      fontsize=8)  # fmt: skip
        axis.grid(alpha=0.3)
        axis.legend(fontsize=8)
    fig.tight_layout()
    figure.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(figure, dpi=110)
    plt.close(fig)


def main() -> None:
    """Run (or reuse) the four margins, print the table, draw the figure."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--cases",
        default="full",
        choices=("full", "quick"),
        help="quick: 4 cases, to check the script (< 2 min)",
    )
    parser.add_argument("--seeds", default="1-4", help="plant seeds, e.g. 1-4, 5-8 or 5,9-10")
    parser.add_argument("--out", default="margin_runs", help="folder of the per-margin JSONs")
    parser.add_argument("--reuse", action="store_true", help="load the JSONs already in --out")
    parser.add_argument("--figure", default="docs/bench/margin_tradeoff.png")
    args = parser.parse_args()
    seeds = parse_seeds(args.seeds)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = [(fraction, run(fraction, name, args.cases, seeds, out, args.reuse))
            for fraction, name in VARIANTS]  # fmt: skip
    print(f"\n{'margin':>7}{'effort median':>15}{'worst':>8}{'drift worst [mrad]':>20}"
          f"{'cases ≥ 1 mrad':>16}")  # fmt: skip
    for fraction, cases in rows:
        effort = np.array([c["effort"] for c in cases.values()])
        drift = np.array([c["drift"] for c in cases.values()])
        print(f"{fraction:>7g}{np.median(effort):>15.2f}{effort.max():>8.2f}"
              f"{drift.max():>20.3g}{int(np.sum(drift >= 1.0)):>16}")  # fmt: skip
    draw(rows, Path(args.figure))
    print(f"figure: {args.figure}")


if __name__ == "__main__":
    main()
