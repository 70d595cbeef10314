"""Cost of one observer update for the YuMi: total, and beyond the dynamics calls.

The update needs M(q), Cᵀq̇, G(q) and the friction mean (and std); what the filter itself
adds is the difference to a call of just those.

Usage:
    python benchmarks/bench_observer.py [--calls N] [--save FILE] [--compare FILE]
"""

from __future__ import annotations

import numpy as np

import leadthrough as lt
from leadthrough.estimation.classical import ClassicalMomentumObserver
from timing import parser, report, time_per_call


def main() -> None:
    args = parser(__doc__.splitlines()[0]).parse_args()
    robot = lt.robots.yumi()
    dynamics = lt.Dynamics(robot)
    friction = lt.FrictionModel.from_robot(robot)
    rng = np.random.default_rng(0)
    q = rng.uniform(robot.q_min, robot.q_max)
    qd = rng.uniform(-0.5, 0.5, robot.n_joints)
    tau = dynamics.gravity(q)

    def model_terms() -> None:
        dynamics.mass(q) @ qd
        dynamics.coriolis_transpose_times_velocity(q, qd) - dynamics.gravity(q)
        friction.mean(qd, q)

    def model_terms_and_std() -> None:
        model_terms()
        friction.std(qd, q)

    observers = {
        "time_varying": lt.MomentumObserver(dynamics, friction, variant="time_varying"),
        "two_level": lt.MomentumObserver(dynamics, friction, variant="two_level"),
        "classical": ClassicalMomentumObserver(dynamics, friction),
    }
    results = {
        "dynamics + friction mean": time_per_call(model_terms, args.calls),
        "dynamics + friction mean + std": time_per_call(model_terms_and_std, args.calls),
    }
    for name, observer in observers.items():
        observer.update(q, qd, tau)
        results[f"update, {name}"] = time_per_call(lambda o=observer: o.update(q, qd, tau),
                                                   args.calls)  # fmt: skip
    print(f"{robot.name}, {args.calls} calls each, one thread")
    report(results, args.save, args.compare)
    base, with_std = results["dynamics + friction mean"], results["dynamics + friction mean + std"]
    for name in observers:
        reference = with_std if name == "time_varying" else base
        extra = results[f"update, {name}"]["median_us"] - reference["median_us"]
        note = ("  (below the separate calls: the compiled step computes M q̇ and the friction"
                " terms itself)" if extra < 0 else "")  # fmt: skip
        print(f"filter cost beyond the model calls, {name}: {extra:.1f} µs{note}")


if __name__ == "__main__":
    main()
