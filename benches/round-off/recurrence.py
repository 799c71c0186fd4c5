"""Generalized-alpha's accelerations of a driven coordinate from its positions
alone (docs/theory.md, "Round-off in the multipliers").

theta_k = 0.5 sin(3 k h) is prescribed, so u_k is given and a_k, v_k, udd_k
follow from the scheme's relations (Arnold & Bruls 2007). Prints the largest
period-2h part, max |D^4 udd| / 16 over t >= 0.1 s, for positions rounded to
doubles (in double and in 40-digit arithmetic) and for exact positions.

    python3 benches/round-off/recurrence.py
"""
from decimal import Decimal, getcontext
import math

getcontext().prec = 40


def dsin(x):
    """sin in Decimal (Taylor series)."""
    term, total, k = x, x, 1
    while abs(term) > Decimal(10) ** -45:
        term = -term * x * x / ((2 * k) * (2 * k + 1))
        total, k = total + term, k + 1
    return total


def accelerations(positions, h, rho, num):
    am, af = (2 * rho - 1) / (rho + 1), rho / (rho + 1)
    g = 0.5 + af - am
    b = 0.25 * (g + 0.5) ** 2
    am, af, g, b, h, half, one = map(num, (am, af, g, b, h, 0.5, 1.0))
    u, v, udd = positions[0], num(1.5), num(0.0)  # v(0) = 1.5, udd(0) = 0
    a = udd + (af - am) * h * num(-13.5)  # the corrected start, jerk -13.5
    out = []
    for u1 in positions[1:]:
        a1 = (u1 - u - h * v - h * h * (half - b) * a) / (b * h * h)
        v += h * ((one - g) * a + g * a1)
        udd = ((one - am) * a1 + am * a - af * udd) / (one - af)
        u, a = u1, a1
        out.append(float(udd))
    return out


def period_2h(x, h):
    skip = int(0.1 / h)
    return max(abs(x[k + 2] - 4 * x[k + 1] + 6 * x[k] - 4 * x[k - 1] + x[k - 2]) / 16
               for k in range(skip, len(x) - 2))


for h in (5e-4, 2.5e-4):
    n = round(1.0 / h)
    rounded = [0.5 * math.sin(3.0 * (k * h)) for k in range(n + 1)]
    exact = [Decimal(0.5) * dsin(Decimal(3) * k * Decimal(h)) for k in range(n + 1)]
    runs = {
        "rounded, double": accelerations(rounded, h, 0.9, float),
        "rounded, 40 digits": accelerations([Decimal(x) for x in rounded], h, 0.9, Decimal),
        "exact, 40 digits": accelerations(exact, h, 0.9, Decimal),
    }
    print(f"h = {h}: " + "; ".join(f"{k} {period_2h(x, h):.3g}" for k, x in runs.items()))
