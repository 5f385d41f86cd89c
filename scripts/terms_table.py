#!/usr/bin/env python3
"""Markdown tables of the IEEE 952 terms an analyser wrote (ieee952_terms.csv), one row per
sensor axis: the fitted range, chi2/dof, N, B, K with their 95 % intervals (or the upper bound
of a term that is not resolved), the region readings beside them, and, when a `sim` truth
file is given, the truth (N: the white level the data show, chain and output LSB included)
and the error of N.

usage: terms_table.py NAME=DIR[:TRUTH_YAML] ...
  DIR holds ieee952_terms.csv; TRUTH_YAML is the <bag>.truth.yaml `sim` wrote (optional).
Used by scripts/profiles.sh and scripts/real_curves.sh.
"""
import csv
import sys

SENSORS = {"gyroscope": "gyro", "accelerometer": "acc"}


def read_terms(path):
    rows = {}
    with open(path, newline="") as f:
        lines = [l for l in f if not l.startswith("#")]
    for r in csv.DictReader(lines):
        rows[(r["sensor"], r["axis"], r["term"])] = r
    return rows


def num(s):
    try:
        return float(s)
    except (TypeError, ValueError):
        return float("nan")


def term_text(r):
    """value [lo, hi] when resolved; '< hi (verdict)' otherwise; the verdict when unusual."""
    if r is None:
        return "–"
    v, lo, hi = num(r["value"]), num(r["ci95_lo"]), num(r["ci95_hi"])
    if r["resolved"] == "true":
        extra = "" if r["verdict"] == "Resolved" else f" ({r['verdict']})"
        return f"{v:.3e} [{lo:.2e}, {hi:.2e}]{extra}"
    if hi == hi and hi < float("inf"):
        return f"< {hi:.2e} ({r['verdict']})"
    return f"– ({r['verdict']})"


def region_text(r):
    if r is None:
        return "–"
    v, lo, hi = num(r["region_value"]), num(r["region_ci95_lo"]), num(r["region_ci95_hi"])
    if v != v:
        return "–"
    if v == 0.0:
        return f"< {hi:.2e}"
    return f"{v:.3e} [{lo:.2e}, {hi:.2e}]"


def truth_of(path):
    import yaml  # PyYAML (Debian python3-yaml), what the truth file's consumers use

    with open(path) as f:
        t = yaml.safe_load(f)
    out = {}
    dt = 1.0 / float(t["output_rate_hz"])
    for sensor, m in t["model"].items():
        disc = t["discrete"][sensor]["axes"]
        for axis, a in m["axes"].items():
            b = a.get("bias_instability")
            # The white level the data show: the chain's (aliasing included) plus the output
            # LSB's rounding error, white at LSB²/12 per sample.
            n_chain = disc[axis].get("white_noise_density_effective", a["white_noise"])
            lsb = float(a.get("resolution") or 0.0)
            out[(sensor, axis)] = {
                "N": (n_chain**2 + lsb**2 / 12.0 * dt) ** 0.5,
                "B": b["value"] if isinstance(b, dict) else 0.0,
                "K": a["random_walk"],
            }
    return out


def main(args):
    for arg in args:
        name, _, rest = arg.partition("=")
        d, _, truth_path = rest.partition(":")
        rows = read_terms(f"{d}/ieee952_terms.csv")
        truth = truth_of(truth_path) if truth_path else None
        print(f"\n### {name}\n")
        head = "| axis | fitted range [s] | χ²/dof | N | B | K | region N / B / K |"
        sep = "|---|---|---|---|---|---|---|"
        if truth:
            head += " truth N / B / K | N error |"
            sep += "---|---|"
        print(head)
        print(sep)
        axes = sorted({(s, a) for (s, a, _) in rows}, key=lambda k: (k[0] != "gyroscope", k[1]))
        for s, a in axes:
            n, b, k = (rows.get((s, a, t)) for t in "NBK")
            base = n or b or k
            lo, hi = num(base["fit_tau_lo"]), num(base["fit_tau_hi"])
            rng = f"{lo:.3g} – {hi:.4g}" if lo == lo else "none"
            rng += f" ({base['fit'].replace('_', ' ')})"
            chi = num(base["chi2_per_dof"])
            line = (
                f"| {SENSORS.get(s, s)} {a} | {rng} | {chi:.2f} | {term_text(n)} | {term_text(b)} | "
                f"{term_text(k)} | {region_text(n)} / {region_text(b)} / {region_text(k)} |"
            )
            if truth:
                t = truth[(s, a)]
                err = (num(n["value"]) / t["N"] - 1.0) * 100.0 if n else float("nan")
                line += f" {t['N']:.3e} / {t['B']:.2e} / {t['K']:.2e} | {err:+.2f} % |"
            print(line)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    main(sys.argv[1:])
