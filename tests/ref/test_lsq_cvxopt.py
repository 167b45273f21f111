#!/usr/bin/env python3
"""Cross-check glint's constrained least-squares solver (core/methods/srbf/lsq.c) against
an independent one, cvxopt's QP (Debian's python3-cvxopt), on random and on
realistic instances: spherical-Gaussian transfer columns like the srbf
method's (147 lobes on the hemicube layout, lambda 81), energy rows with a
diffuse unknown, targets brighter than energy allows, semidefinite and
degenerate problems, infeasible budgets.

    python3 test_lsq_cvxopt.py PATH/TO/lsq_tool

Asserts: objectives agree to 1e-6 relative (objective = ||Tc - f||^2 =
c'Hc - 2q'c + f'f, compared on the larger of the two and f'f), glint's
constraints hold to 1e-9 of the scale of u, and the infeasible case is
reported as infeasible.  Prints a table with both objectives, iterations
and times.  Exits 77 (skipped) when cvxopt is missing."""
import json
import math
import os
import subprocess
import sys
import tempfile
import time

try:
    import numpy as np
    from cvxopt import matrix, solvers
except ImportError as exc:  # pragma: no cover
    print(f"SKIP: {exc}")
    sys.exit(77)

solvers.options.update({"show_progress": False, "abstol": 1e-13, "reltol": 1e-13,
                        "feastol": 1e-12, "maxiters": 400})
TOOL = sys.argv[1]


def hemicube(r):
    """The lobe centres of core/methods/srbf/srbf.h (the same formula, written again)."""
    out = []
    u = [-1 + (2 * a + 1) / r for a in range(r)]
    for b in range(r):
        for a in range(r):
            out.append((u[a], u[b], 1.0))
    def side(f, x, z):
        return [(1, x, z), (-x, 1, z), (-1, -x, z), (x, -1, z)][f]
    for f in range(4):
        for row in range(r):
            z = -1 + (2 * row + 1) / r
            if z <= 1e-12:
                continue
            for a in range(r):
                out.append(side(f, u[a], z))
    if r % 2:
        for ring in range(0, 4 * r, 2):
            out.append(side(ring // r, u[ring % r], 0.0))
    x = np.array(out, float)
    return x / np.linalg.norm(x, axis=1)[:, None]


def solve_glint(H, q, ff, G, u, mode, reps=5):
    n, m = len(q), (len(u) if G is not None else 0)
    with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as f:
        f.write(f"{n} {m} {mode}\n")
        for arr in (H.ravel(), q, [ff]):
            f.write(" ".join(repr(float(v)) for v in arr) + "\n")
        if m:
            f.write(" ".join(repr(float(v)) for v in G.ravel()) + "\n")
            f.write(" ".join(repr(float(v)) for v in u) + "\n")
        path = f.name
    try:
        out = subprocess.run([TOOL, path, str(reps)], capture_output=True, text=True, check=True)
    finally:
        os.unlink(path)
    return json.loads(out.stdout)


def solve_cvxopt(H, q, G, u, mode):
    n = len(q)
    s = max(np.abs(H).max(), 1e-300)
    P = matrix(H / s)
    qq = matrix(-q / s)
    if mode == 2:
        c = np.linalg.lstsq(H, q, rcond=None)[0]
        return c, 0.0
    rows = [-np.eye(n)]
    h = [np.zeros(n)]
    if mode == 0 and G is not None and len(u):
        rows.append(G)
        h.append(u)
    t0 = time.perf_counter()
    sol = solvers.qp(P, qq, matrix(np.vstack(rows)), matrix(np.concatenate(h)))
    dt = time.perf_counter() - t0
    return np.array(sol["x"]).ravel(), dt


def objective(H, q, ff, c, Tf=None):
    """||Tc - f||^2 from T and f when known (c'Hc - 2q'c + f'f cancels
    to the rounding of f'f when the fit is close)."""
    if Tf is not None:
        r = Tf[0] @ c - Tf[1]
        return float(r @ r)
    return float(c @ H @ c - 2 * q @ c + ff)


def realistic(rng, N=2000, lam=81.0, diffuse=True, bright=1.5):
    xi = hemicube(7)
    J = len(xi)
    # half vectors around +z, weighted like a lit sphere's pixels
    h = rng.normal(size=(N, 3)) * [0.35, 0.35, 0.0] + [0, 0, 1]
    h /= np.linalg.norm(h, axis=1)[:, None]
    T = np.exp(lam * (h @ xi.T - 1.0)) * rng.uniform(0.2, 1.0, size=(N, 1))
    E = rng.uniform(0.5, 1.0, size=N)
    cstar = np.exp(-(1 - xi[:, 2]) / 0.03)
    cstar[cstar < 0.03 * cstar.max()] = 0
    # energy rows: the lobes' albedo at 300 outgoing directions, a smooth
    # positive kernel standing in for the quadrature
    wo = rng.normal(size=(300, 3))
    wo[:, 2] = np.abs(wo[:, 2])
    wo /= np.linalg.norm(wo, axis=1)[:, None]
    g = 0.02 * np.exp(8.0 * (wo @ xi.T - 1.0)) * (0.5 + wo[:, 2:3])
    rho = 0.3
    cstar *= 0.8 * (1 - rho) / (g @ cstar).max()
    cstar = cstar[None, :]
    f = bright * (T @ cstar[0] + rho * E) + rng.normal(scale=0.01, size=N)
    # the lobes the half vectors reach, as the method keeps them
    keep = T.max(axis=0) > 1e-6 * T.max()
    T, g = T[:, keep], g[:, keep]
    if diffuse:
        T = np.hstack([T, E[:, None]])
        g = np.hstack([g, np.ones((300, 1))])
        u = np.full(300, 1.0)
    else:
        f = f - rho * E
        u = np.full(300, 1.0 - rho)
    return T.T @ T, T.T @ f, float(f @ f), g, u, (T, f)


def random_instance(rng, n, m, N):
    A = rng.normal(size=(N, n))
    f = rng.normal(size=N) + A @ np.abs(rng.normal(size=n))
    G = np.abs(rng.normal(size=(m, n)))
    u = np.abs(rng.normal(size=m)) + 0.1
    return A.T @ A, A.T @ f, float(f @ f), G, u, (A, f)


def main():
    rng = np.random.default_rng(7)
    cases = []
    for k in range(6):
        cases.append((f"random n=20 m=30 #{k}", 0) + random_instance(rng, 20, 30, 60))
    for k in range(3):
        cases.append((f"random n=60 m=100 #{k}", 0) + random_instance(rng, 60, 100, 200))
    cases.append(("random nonneg n=40", 1) + random_instance(rng, 40, 0, 120))
    for k in range(2):
        cases.append((f"srbf J=147 fixed diffuse #{k}", 0) + realistic(rng, diffuse=False))
        cases.append((f"srbf J=147+diffuse, 1.5x too bright #{k}", 0) + realistic(rng))
        cases.append((f"srbf J=147+diffuse, 3x too bright #{k}", 0) + realistic(rng, bright=3.0))
    cases.append(("srbf nonneg only", 1) + realistic(rng))
    H, q, ff, G, u, Tf = random_instance(rng, 12, 8, 40)
    Hd = np.zeros((13, 13))
    Hd[:12, :12] = H
    Hd[12, :12] = Hd[:12, 12] = H[0]
    Hd[12, 12] = H[0, 0]  # a duplicated column: H semidefinite
    Td = (np.hstack([Tf[0], Tf[0][:, :1]]), Tf[1])
    cases.append(("duplicate column (semidefinite)", 0, Hd, np.append(q, q[0]), ff,
                  np.hstack([G, G[:, :1]]), u, Td))
    u0 = u.copy()
    u0[3] = 0.0
    cases.append(("a zero budget row", 0, H, q, ff, G, u0, Tf))
    for sc in (1e-8, 1e8):
        cases.append((f"scaled by {sc:g}", 0, H * sc, q * sc, ff * sc, G, u,
                      (Tf[0] * math.sqrt(sc), Tf[1] * math.sqrt(sc))))

    fails = 0
    print(f"{'case':42s} {'glint objective':>22s} {'cvxopt objective':>22s} {'rel diff':>9s} "
          f"{'viol':>8s} {'it':>4s} {'glint ms':>8s} {'cvxopt ms':>9s}")
    for name, mode, H, q, ff, G, u, Tf in cases:
        g = solve_glint(H, q, ff, G, u, mode)
        if "error" in g:
            print(f"{name}: glint error {g['error']}")
            fails += 1
            continue
        c = np.array(g["c"])
        cc, dt = solve_cvxopt(H, q, G, u, mode)
        og, oc = objective(H, q, ff, c, Tf), objective(H, q, ff, cc, Tf)
        scale = max(abs(og), abs(oc), ff * 1e-12, 1e-300)
        rel = (og - oc) / scale
        viol = 0.0
        if mode != 2:
            viol = max(viol, float(-c.min()))
        if mode == 0 and G is not None and len(u):
            viol = max(viol, float((G @ c - u).max()) / max(1.0, float(np.abs(u).max())))
        # the same problem with the rows and the factor of H kept by the caller
        ck = np.array(g["c_kept"])
        relk = (objective(H, q, ff, ck, Tf) - oc) / scale
        if mode != 2:
            viol = max(viol, float(-ck.min()))
        if mode == 0 and G is not None and len(u):
            viol = max(viol, float((G @ ck - u).max()) / max(1.0, float(np.abs(u).max())))
        rel = max(rel, relk)
        ok = g["status"] == "optimal" and rel <= 1e-6 and viol <= 1e-9
        fails += not ok
        print(f"{name:42s} {og:22.15g} {oc:22.15g} {rel:9.1e} {viol:8.1e} {g['iterations']:4d} "
              f"{g['ms']:8.3f} {dt * 1e3:9.2f}{'' if ok else '  FAIL'}")
    # an infeasible budget: a row with u < 0 (a diffuse albedo above 1)
    H, q, ff, G, u, _ = random_instance(rng, 10, 5, 30)
    u[2] = -0.2
    g = solve_glint(H, q, ff, G, u, 0)
    inf_ok = g.get("status") == "infeasible" and g.get("infeasible_row") == 2
    print(f"infeasible budget (u[2] = -0.2): status {g.get('status')}, row "
          f"{g.get('infeasible_row')}{'' if inf_ok else '  FAIL'}")
    fails += not inf_ok
    print(f"{len(cases) + 1 - fails} passed, {fails} failed")
    sys.exit(1 if fails else 0)


if __name__ == "__main__":
    main()
