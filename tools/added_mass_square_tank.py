#!/usr/bin/python3
"""Added-mass coefficient of a circular cylinder at the centre of a closed square tank, 2D potential flow.

The reference of tests/validation/test_oscillating_cylinder.cpp (scenes/oscillating_cylinder_2d.yaml).
The potential of the cylinder moving along x at unit speed is written as the multipole series

    phi = sum over odd k of (alpha_k (a/r)^k + beta_k (r/b)^k) cos(k theta),

which is harmonic, even in y and odd in x; the body condition dphi/dr = cos(theta) on r = a holds
exactly term by term, the walls' dphi/dn = 0 (x = b, y = b; symmetry gives the others) in least
squares at collocation points. The added mass per unit length is m_a = -rho * integral of phi n_x
over the circle, so C_a = m_a / (rho pi a^2) = -(alpha_1 / a + beta_1 / b). The series converges
fast (the wall residual falls below 1e-9 with 41 terms); in a wide tank it gives C_a -> 1, and it lies
between the values for the concentric circular tanks inside and around the square,
(1 + e) / (1 - e) with e = (a / b)^2 and (a / (b sqrt 2))^2.

Usage: tools/added_mass_square_tank.py RADIUS HALF_SIDE   (e.g. 0.1 0.5 -> C_a = 1.0712)
"""
import sys

import numpy as np


def added_mass_coefficient(a, b, terms=41, points=801):
    ks = np.arange(1, terms + 1, 2)

    def grad(p, k, scale, x, y):
        r = np.hypot(x, y)
        th = np.arctan2(y, x)
        f = (r / scale) ** p
        gr = p * f / r * np.cos(k * th)
        gt = -k * f / r * np.sin(k * th)
        return gr * np.cos(th) - gt * np.sin(th), gr * np.sin(th) + gt * np.cos(th)

    s = np.linspace(-b, b, points)
    walls = []
    for x, y, nx, ny in [(np.full_like(s, b), s, 1.0, 0.0), (s, np.full_like(s, b), 0.0, 1.0)]:
        cols = []
        for k in ks:
            gx, gy = grad(-k, k, a, x, y)
            cols.append(gx * nx + gy * ny)
            gx, gy = grad(k, k, b, x, y)
            cols.append(gx * nx + gy * ny)
        walls.append(np.array(cols).T)
    weight = 1e4  # the body condition, exact to the least-squares solve's rounding
    body = np.zeros((len(ks), 2 * len(ks)))
    rhs_body = np.zeros(len(ks))
    for j, k in enumerate(ks):
        body[j, 2 * j] = -k / a * weight
        body[j, 2 * j + 1] = k * (a / b) ** (k - 1) / b * weight
        rhs_body[j] = weight if k == 1 else 0.0
    wall = np.vstack(walls)
    matrix = np.vstack([wall, body])
    rhs = np.concatenate([np.zeros(wall.shape[0]), rhs_body])
    c, *_ = np.linalg.lstsq(matrix, rhs, rcond=None)
    return -(c[0] / a + c[1] / b), float(np.abs(wall @ c).max())


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    a, b = float(sys.argv[1]), float(sys.argv[2])
    ca, residual = added_mass_coefficient(a, b)
    e = (a / b) ** 2
    print(f"C_a = {ca:.5f} (wall residual {residual:.1e}); concentric circular tanks: "
          f"{(1 + e / 2) / (1 - e / 2):.5f} (radius b sqrt 2) .. {(1 + e) / (1 - e):.5f} (radius b)")
