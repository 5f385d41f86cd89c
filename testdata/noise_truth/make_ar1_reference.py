#!/usr/bin/env python3
"""Reference values of the Allan variance of a unit-variance AR(1) sequence (a = exp(-beta))
at cluster size m, in 40-digit arithmetic (mpmath), for sim's noise::truth tests:
    m^2 * AVAR = [m(1+a)(1-a) - a(1-a^m)(3-a^m)] / (1-a)^2
Run: python3 make_ar1_reference.py > ar1_avar_mpmath.csv"""
from mpmath import mp, mpf, exp

mp.dps = 40
import mpmath
print("# AR(1) Allan variance per unit variance (a = exp(-beta), cluster size m); mpmath %s at 40 digits; written by make_ar1_reference.py" % mpmath.__version__)
print("beta,m,avar")
for beta in ["1e-9", "1e-7", "1e-5", "1e-4", "1e-3", "0.01", "0.05", "0.1", "0.2", "0.5", "1", "3"]:
    b = mpf(beta)
    a = exp(-b)
    for m in [1, 2, 3, 5, 10, 19, 20, 21, 100, 1000, 10000, 100000, 1000000]:
        mm = mpf(m)
        am = a ** m
        br = (mm * (1 + a) * (1 - a) - a * (1 - am) * (3 - am)) / (1 - a) ** 2
        v = br / mm ** 2
        print("%s,%d,%s" % (beta, m, mp.nstr(v, 25, min_fixed=-1, max_fixed=-1)))
