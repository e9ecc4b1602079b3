#!/usr/bin/env python3
"""The error of src/lane_math.rs's functions against mpmath, in units in the last place.

Reads the samples `cargo test --release --locked --lib lane_math::tests::write_samples_for_mpmath
-- --ignored` writes (target/lane_math_samples.csv: function, argument bits, result bits) and
prints, per function, the largest error in ulp of the correctly rounded value and where.
Needs mpmath (pip install mpmath). Usage: python3 scripts/lane_math_error.py [CSV]
"""
import csv
import struct
import sys

import mpmath as mp

mp.mp.dps = 40


def f64(bits):
    return struct.unpack("<d", struct.pack("<Q", int(bits, 16)))[0]


def ulp_error(got, exact):
    """|got - exact| in ulps of exact's binade (subnormal spacing below 2^-1022)."""
    if exact == 0 or mp.isinf(exact):
        return 0.0 if got == float(exact) else float("inf")
    e = max(int(mp.floor(mp.log(abs(exact), 2))), -1022)
    return float(abs(mp.mpf(got) - exact) / mp.mpf(2) ** (e - 52))


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "target/lane_math_samples.csv"
    exact = {
        "sin": lambda x, y: mp.sin(x),
        "cos": lambda x, y: mp.cos(x),
        "expm1": lambda x, y: mp.expm1(x),
        "atan2": lambda x, y: mp.atan2(y, x),
        "ln": lambda x, y: mp.log(x),
        "ln_1p": lambda x, y: mp.log1p(x),
    }
    worst = {}
    count = {}
    with open(path) as f:
        for row in csv.DictReader(f):
            fn = row["function"]
            x, y, got = f64(row["x"]), f64(row["y"]), f64(row["result"])
            err = ulp_error(got, exact[fn](mp.mpf(x), mp.mpf(y)))
            count[fn] = count.get(fn, 0) + 1
            if err > worst.get(fn, (-1,))[0]:
                worst[fn] = (err, x, y)
    for fn, (err, x, y) in sorted(worst.items()):
        where = f"x = {x!r}" + (f", y = {y!r}" if fn == "atan2" else "")
        print(f"{fn:6} {count[fn]:8} samples  max {err:.3f} ulp  at {where}")


if __name__ == "__main__":
    main()
