#!/usr/bin/env python3
"""The polynomials of src/lane_math.rs: near-minimax fits, in 50-digit arithmetic.

Each polynomial approximates the part of a function its reduction leaves after the leading
terms, weighted by that part's share of the function's relative error:
  sin   S(z) ~ (sin r - r)/r^3,            z = r^2, |r| <= pi/4,        weight r^2, degree 5
  cos   C(z) ~ (cos r - 1 + r^2/2)/r^4,    z = r^2, |r| <= pi/4,        weight r^4, degree 5
  atan  A(z) ~ (atan u - u)/u^3,           z = u^2, |u| <= tan(pi/8),   weight u^2, degree 10
  expm1 P(r) ~ (expm1 r - r - r^2/2)/r^3,           |r| <= ln(2)/2,     weight r^2, degree 9
  ln    Q(z) ~ (2 atanh s - 2 s)/s^3,      z = s^2, |s| <= (sqrt2-1)/(sqrt2+1), weight s^2, degree 6
(each interval widened by 1e-4 for the reductions' rounding). The fit is Lawson's
iteratively reweighted least squares on 400 Chebyshev points, which converges to the
weighted minimax polynomial on those points. Prints the weighted maximum error and the
coefficients, lowest first, as f64 bit patterns for the Rust source; with `f32`, as the
shortest decimals that round to the coefficients' f32 values, for the f32 kernels' `ktrig`
(src/model/real.rs) and its WGSL twin (shaders/shared/trig.wgsl), which use degrees 2, 2, 3.
Needs mpmath. Usage: python3 scripts/fit_polynomials.py {sin|cos|atan|expm1|ln} DEGREE [f32]
"""
import struct
import sys

import mpmath as mp

mp.mp.dps = 50


def lawson(g, a, b, deg, var, weight, iters=25, m=400):
    """Weighted minimax of sum c_j var(x)^j against g on m Chebyshev points of [a, b]."""
    xs = [(a + b) / 2 + (b - a) / 2 * mp.cos(mp.pi * (2 * i + 1) / (2 * m)) for i in range(m)]
    vs = [var(x) for x in xs]
    gs = [g(x) for x in xs]
    ws = [weight(x) for x in xs]
    lam = [mp.mpf(1) / m] * m
    n = deg + 1
    for _ in range(iters):
        A = mp.matrix(m, n)
        y = mp.matrix(m, 1)
        for i in range(m):
            s = mp.sqrt(lam[i]) * ws[i]
            for j in range(n):
                A[i, j] = s * vs[i] ** j
            y[i] = s * gs[i]
        c, _ = mp.qr_solve(A, y)
        errs = [abs(ws[i] * (sum(c[j] * vs[i] ** j for j in range(n)) - gs[i])) for i in range(m)]
        total = sum(lam[i] * errs[i] for i in range(m))
        lam = [lam[i] * errs[i] / total for i in range(m)]
    return [c[j] for j in range(n)], max(errs)


def fit(which, deg):
    pi, widen = mp.pi, mp.mpf("1.0001")
    if which == "sin":
        return lawson(lambda r: (mp.sin(r) - r) / r**3, mp.mpf(0), pi / 4 * widen, deg, lambda r: r * r, lambda r: r * r)
    if which == "cos":
        return lawson(lambda r: (mp.cos(r) - 1 + r * r / 2) / r**4, mp.mpf(0), pi / 4 * widen, deg, lambda r: r * r, lambda r: r**4)
    if which == "atan":
        t8 = mp.tan(pi / 8) * widen
        return lawson(lambda u: (mp.atan(u) - u) / u**3, mp.mpf(0), t8, deg, lambda u: u * u, lambda u: u * u)
    if which == "ln":
        smax = (mp.sqrt(2) - 1) / (mp.sqrt(2) + 1) * widen
        return lawson(lambda s: (2 * mp.atanh(s) - 2 * s) / s**3, mp.mpf(0), smax, deg, lambda s: s * s, lambda s: s * s)
    if which == "expm1":
        h = mp.log(2) / 2 * widen
        return lawson(lambda r: (mp.expm1(r) - r - r * r / 2) / r**3, -h, h, deg, lambda r: r, lambda r: r * r)
    raise SystemExit(f"fit_polynomials.py: unknown function {which!r} (sin, cos, atan, expm1, ln)")


def f32(x):
    """x rounded to the nearest f32."""
    return struct.unpack("<f", struct.pack("<f", float(x)))[0]


def shortest_f32(x):
    """The shortest decimal that rounds to the same f32 as x."""
    for digits in range(1, 12):
        text = "%.*e" % (digits, f32(x))
        if f32(float(text)) == f32(x):
            return text
    raise AssertionError(x)


if __name__ == "__main__":
    if len(sys.argv) not in (3, 4) or not sys.argv[2].isdigit() or sys.argv[3:] not in ([], ["f32"]):
        raise SystemExit("usage: fit_polynomials.py {sin|cos|atan|expm1|ln} DEGREE [f32]")
    coeffs, err = fit(sys.argv[1], int(sys.argv[2]))
    print(f"{sys.argv[1]} degree {sys.argv[2]}: weighted max error {mp.nstr(err, 5)} = 2^{mp.nstr(mp.log(err, 2), 4)}")
    if sys.argv[3:] == ["f32"]:
        print("    " + ", ".join(shortest_f32(c) for c in coeffs))
        raise SystemExit(0)
    for c in coeffs:
        bits = struct.unpack("<Q", struct.pack("<d", float(c)))[0]
        print(f"    f64::from_bits(0x{bits >> 48:04x}_{(bits >> 32) & 0xffff:04x}_{(bits >> 16) & 0xffff:04x}_{bits & 0xffff:04x}),")
