"""Power analysis of a perception-study protocol from simulated cohorts.

A pool of simulated participants (the observer model of ``rigidtouch study simulate``, each with
its own seed) is run once on the protocol; cohorts of n participants are then drawn from the pool
without replacement, many times for each n. Each test of the protocol is analysed per cohort the
way a lab would: a one-sided one-sample t-test of the participants' percent correct against
chance (50 %; 100/k % for a test of k walls), alpha 0.05. The power at n is the fraction of cohorts in which the test is
significant; the answer is the smallest n whose power reaches the target (80 %).

    python3 -m rigidtouch.power --protocol studies/walls.json
"""

import argparse
import json
import math
import random
import sys


def _betacf(a, b, x):
    # continued fraction of the regularized incomplete beta function (modified Lentz)
    tiny = 1e-300
    c, d = 1.0, 1.0 - (a + b) * x / (a + 1.0)
    d = 1.0 / (d if abs(d) > tiny else tiny)
    h = d
    for m in range(1, 300):
        m2 = 2 * m
        for num in (m * (b - m) * x / ((a + m2 - 1) * (a + m2)),
                    -(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1))):
            d = 1.0 + num * d
            d = 1.0 / (d if abs(d) > tiny else tiny)
            c = 1.0 + num / c
            c = c if abs(c) > tiny else tiny
            h *= d * c
        if abs(d * c - 1.0) < 1e-15:
            break
    return h


def betainc(a, b, x):
    """Regularized incomplete beta function I_x(a, b), x in [0, 1]."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    front = math.exp(math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b)
                     + a * math.log(x) + b * math.log1p(-x))
    if x < (a + 1.0) / (a + b + 2.0):
        return front * _betacf(a, b, x) / a
    return 1.0 - front * _betacf(b, a, 1.0 - x) / b


def t_sf(t, df):
    """P(T > t) for Student's t with df degrees of freedom."""
    tail = 0.5 * betainc(df / 2.0, 0.5, df / (df + t * t))
    return tail if t >= 0 else 1.0 - tail


def one_sided_t_p(values, mu0):
    """p of the one-sided one-sample t-test that the mean of `values` exceeds mu0."""
    n = len(values)
    mean = sum(values) / n
    var = sum((v - mean) ** 2 for v in values) / (n - 1)
    if var == 0.0:
        return 0.0 if mean > mu0 else 1.0
    return t_sf((mean - mu0) / math.sqrt(var / n), n - 1)


def power_analysis(protocol, *, pool=60, seed=1, cohorts=2000, alpha=0.05, target=0.8,
                   max_n=None, observer="", scene="", device=""):
    """Participants needed for `target` power on each test of `protocol` (a JSON file).
    Returns {"tests": [{"name", "participants_needed", "power": {n: power}}], ...}."""
    import rigidtouch
    report = rigidtouch.simulate_cohort(protocol, pool, seed, observer=observer, scene=scene,
                                        device=device)
    rng = random.Random(seed)
    max_n = min(max_n or pool, pool)
    # chance is 1/k for a test of k walls (the report's "chance"; 1/2 for two)
    chances = [100.0 * test.get("chance", 0.5) for test in report["tests"]]
    against = ("50 %" if all(c == 50.0 for c in chances)
               else "chance, 100/k % for a test of k walls")
    out = {"protocol": protocol, "pool": pool, "seed": seed, "cohorts_per_size": cohorts,
           "alpha": alpha, "target_power": target,
           "test": "one-sided one-sample t-test of percent correct against " + against,
           "tests": []}
    for test, chance in zip(report["tests"], chances):
        scores = [p["percent_correct"] for p in test["participants"]]
        powers = {}
        needed = None
        for n in range(2, max_n + 1):
            hits = sum(one_sided_t_p(rng.sample(scores, n), chance) < alpha
                       for _ in range(cohorts))
            powers[n] = hits / cohorts
            if powers[n] >= target:
                needed = n
                break
        out["tests"].append({"name": test["name"], "conditions": test["conditions"],
                             "pool_mean_percent_correct": test["mean_percent_correct"],
                             "pool_sd": test["sd"], "chance_percent": chance,
                             "participants_needed": needed,
                             "power": powers})
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m rigidtouch.power", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--protocol", required=True, help="study protocol (JSON)")
    parser.add_argument("--pool", type=int, default=60, help="simulated participants in the pool")
    parser.add_argument("--seed", type=int, default=1, help="seed of the pool and the draws")
    parser.add_argument("--cohorts", type=int, default=2000, help="cohorts drawn per size")
    parser.add_argument("--target", type=float, default=0.8, help="power wanted")
    parser.add_argument("--alpha", type=float, default=0.05, help="significance level")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    if args.pool < 2 or args.cohorts < 1 or not 0 < args.target < 1 or not 0 < args.alpha < 1:
        print("rigidtouch: error: --pool >= 2, --cohorts >= 1, --target and --alpha in (0, 1)",
              file=sys.stderr)
        return 2
    try:
        result = power_analysis(args.protocol, pool=args.pool, seed=args.seed,
                                cohorts=args.cohorts, alpha=args.alpha, target=args.target)
    except ValueError as e:
        print(f"rigidtouch: error: {e}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(result))
        return 0
    print(f"{result['protocol']}: {result['test']}, alpha {args.alpha}; cohorts drawn from "
          f"{args.pool} simulated participants (seed {args.seed}), {args.cohorts} per size")
    for t in result["tests"]:
        need = t["participants_needed"]
        last = max(t["power"]) if t["power"] else None
        print(f"  {t['name']} ({' vs '.join(t['conditions'])}): pool mean "
              f"{t['pool_mean_percent_correct']:.1f} % correct (SD {t['pool_sd']:.1f}); "
              + (f"{need} participants for {100 * args.target:.0f} % power "
                 f"(power {100 * t['power'][need]:.1f} %)" if need else
                 f"{100 * args.target:.0f} % power not reached with {last} participants"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
