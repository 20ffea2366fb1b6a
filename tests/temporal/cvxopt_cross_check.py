#!/usr/bin/python3
"""Cross-check of `timeopt temporal` against an independent formulation and solver.

The temporal problem is written here a second time, from docs/temporal.md ("The discretized
problem") and docs/formats.md (the problem JSON) alone (velocity at grid points, acceleration at
cell middles, joints with parallel tangents by eq. 42 and a stop at kinks, boundary speeds along the
tangent, the acceleration-change rows, rho, curves given with `durations`; and, for every third
problem, certified mode: every Bernstein coefficient of the velocity and acceleration polynomials
of every cell within the limits), as a second-order cone program for CVXOPT's conelp (Debian's
python3-cvxopt, an interior-point solver of its own). The random curves (cubic and quintic, C1 or
only G1 in s) are generated here, so they are not in the repository. Each problem is solved by
`timeopt temporal --solver socp` and `--solver ipopt` and by CVXOPT.

Paper mode: T and J must agree to 1e-6 relative (T to 1e-5 when rho > 0, see below). All three
solvers stop at gaps near 1e-8, so the margin is about 100, while a difference in the rows shows at
once: moving the acceleration sample from the cell middle to 0.45 of the cell in this script alone
made every paper-mode problem fail (T off by up to 7.6e-3; one became infeasible).
Certified mode: timeopt thins runs of nearly parallel coefficient rows by tightening their neighbours
(never loosening), which may raise T by up to 3e-4 relative: timeopt's T and J must lie in
[-1e-6, 3e-4 + 1e-6] relative to the exact rows here. Dropping the velocity coefficients here, or
tightening one of them by 1%, made every certified problem fail.

Exit codes: 0 all agree, 1 a disagreement (each printed), 77 skipped (CVXOPT or numpy missing).
Usage: cvxopt_cross_check.py TIMEOPT_EXECUTABLE [--problems N] [--seed S] [--keep DIR]
"""

import argparse
import json
import math
import os
import random
import subprocess
import sys
import tempfile
import time

try:
    import numpy as np
    from cvxopt import matrix, solvers, spmatrix
except ImportError as error:  # the test is skipped, saying why
    print(f"SKIP: {error} (install Debian's python3-cvxopt and python3-numpy)")
    sys.exit(77)

TOLERANCE = 1e-6
CERTIFIED_THINNING_BOUND = 3e-4  # half of TemporalProblem::certified_thinning's default


def hermite_piece(p0, t0, p1, t1, bump, rng):
    """Power-basis coefficients (ascending, per axis) of the cubic through p0, p1 with tangents t0, t1
    at s = 0, 1; `bump` adds s^2 (1 - s)^2 (alpha + beta s), which keeps both ends, making it a
    quintic. The columns are the polynomial's own degree (no trailing zeros)."""
    coef = np.zeros((3, 6 if bump else 4))
    coef[:, 0] = p0
    coef[:, 1] = t0
    coef[:, 2] = -3 * p0 - 2 * t0 + 3 * p1 - t1
    coef[:, 3] = 2 * p0 + t0 - 2 * p1 + t1
    if bump:
        # s^2 (1-s)^2 = s^2 - 2 s^3 + s^4; times (alpha + beta s).
        alpha = np.array([rng.uniform(-3, 3) for _ in range(3)])
        beta = np.array([rng.uniform(-3, 3) for _ in range(3)])
        coef[:, 2] += alpha
        coef[:, 3] += -2 * alpha + beta
        coef[:, 4] += alpha - 2 * beta
        coef[:, 5] += beta
    return coef


def random_problem(rng, mode):
    pieces = rng.randint(1, 4)
    points = [np.zeros(3)]
    for _ in range(pieces):
        points.append(points[-1] + np.array([rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-1.5, 1.5)]))
    tangents = []
    for i in range(pieces + 1):
        a = points[max(i - 1, 0)]
        b = points[min(i + 1, pieces)]
        t = 0.5 * (b - a) * (2.0 if i in (0, pieces) else 1.0)
        t += np.array([rng.uniform(-1, 1) for _ in range(3)])
        if np.linalg.norm(t) < 1.0:
            t = t / max(np.linalg.norm(t), 1e-3)
        tangents.append(t)
    bump = rng.random() < 0.5
    # Half of the curves are only G1 in s: at a joint the next piece starts with the tangent scaled
    # by kappa (what a time-parameterized planner's pieces become once rescaled to unit pieces).
    g1 = rng.random() < 0.5
    kappa = [rng.uniform(0.5, 2.0) if g1 else 1.0 for _ in range(pieces + 1)]
    # Some joints are kinks: the next piece starts in another direction, and the vehicle must stop.
    start_tangents = [kappa[i] * tangents[i] if i > 0 else tangents[i] for i in range(pieces)]
    for i in range(1, pieces):
        if rng.random() < 0.25:
            turn = np.array([rng.uniform(-1, 1) for _ in range(3)])
            start_tangents[i] = np.linalg.norm(tangents[i]) * (tangents[i] + 2.0 * turn) / np.linalg.norm(
                tangents[i] + 2.0 * turn)
    coefs = [hermite_piece(points[i], start_tangents[i], points[i + 1], tangents[i + 1], bump, rng)
             for i in range(pieces)]
    vmax = [rng.uniform(1.0, 4.0) for _ in range(3)]
    amax = [rng.uniform(1.0, 4.0) for _ in range(3)]
    problem = {
        "curve": {"pieces": [{"x": c[0].tolist(), "y": c[1].tolist(), "z": c[2].tolist()} for c in coefs]},
        "limits": {"max_velocity": vmax, "max_acceleration": amax},
        "discretization": {"K": rng.choice([8, 12, 16, 20])},
        "rho": rng.choice([0.0, 0.0, 0.1, 1.0]),
        "constraint_mode": mode,
    }
    boundary = {"start_velocity": [0.0] * 3, "start_acceleration": [0.0] * 3,
                "end_velocity": [0.0] * 3, "end_acceleration": [0.0] * 3}
    if rng.random() < 0.4:
        # A start speed along the tangent, a fifth of what the velocity limit allows there.
        t0 = tangents[0]
        cap = min(vmax[j] / abs(t0[j]) for j in range(3) if abs(t0[j]) > 0)
        boundary["start_velocity"] = (0.2 * cap * t0).tolist()
    if rng.random() < 0.3:
        problem["limits"]["max_acceleration_change"] = rng.uniform(0.5, 2.0)
    problem["boundary"] = boundary
    if rng.random() < 0.3:
        # The same curve as a time-parameterized planner writes it: piece i in tau in [0, h_i], so
        # the coefficient of tau^j is c_j / h_i^j (docs/formats.md: rescaled to s = tau / h_i on
        # input).
        durations = [rng.uniform(0.5, 3.0) for _ in range(pieces)]
        problem["curve"] = {
            "durations": durations,
            "pieces": [{axis: (c[a] / durations[i] ** np.arange(c.shape[1])).tolist()
                        for a, axis in enumerate("xyz")} for i, c in enumerate(coefs)],
        }
    return problem, coefs


def derivatives(coef, s):
    """f'(s), f''(s) of one piece (3 x (degree + 1) ascending coefficients)."""
    d1 = np.zeros(3)
    d2 = np.zeros(3)
    for j in range(1, coef.shape[1]):
        d1 += j * coef[:, j] * s ** (j - 1)
        if j >= 2:
            d2 += j * (j - 1) * coef[:, j] * s ** (j - 2)
    return d1, d2


def bernstein(poly):
    """Bernstein coefficients on [0, 1], at the polynomial's own degree, of a power-basis
    polynomial (ascending coefficients): beta_k = sum_{i <= k} C(k, i) / C(D, i) a_i."""
    a = list(poly)
    D = len(a) - 1
    return [sum(math.comb(k, i) / math.comb(D, i) * a[i] for i in range(k + 1)) for k in range(D + 1)]


def certified_rows(coefs, cells, ds, vmax, amax, b_terms, less_equal):
    """Certified mode (docs/temporal.md, "The discretized problem"): on a cell, with u in [0, 1],
    s = s_k + u ds, b = (1 - u) b0 + u b1 and a = (b1 - b0) / (2 ds), every Bernstein coefficient of
    f'(s)^2 b and of f'(s) a + f''(s) b (linear in b0, b1) is within the limits."""
    P = np.polynomial.Polynomial
    one_minus_u, u = P([1.0, -1.0]), P([0.0, 1.0])
    for g0, g1, i, k in cells:
        shift = P([k * ds, ds])
        for j in range(3):
            f = P(coefs[i][j])
            q = f.deriv(1)(shift)
            p = f.deriv(2)(shift) if f.degree() >= 2 else P([0.0])
            if np.any(q.coef != 0.0):
                w0 = bernstein((q * q * one_minus_u).coef)
                w1 = bernstein((q * q * u).coef)
                w0[-1] = 0.0  # exactly: b0's weight vanishes at u = 1, b1's at u = 0
                w1[0] = 0.0
                for c0, c1 in zip(w0, w1):
                    less_equal([b_terms(g0, c0), b_terms(g1, c1)], vmax[j] ** 2)
            # Both weights at the degree of f' a + f'' b: max(deg f', deg f'' + 1).
            size = max(len(q.coef), len((p * u).coef))

            def padded(poly):
                c = list(poly.coef)
                return c + [0.0] * (size - len(c))

            c0 = bernstein(padded(-q / (2 * ds) + p * one_minus_u))
            c1 = bernstein(padded(q / (2 * ds) + p * u))
            for x0, x1 in zip(c0, c1):
                less_equal([b_terms(g0, x0), b_terms(g1, x1)], amax[j])
                less_equal([b_terms(g0, -x0), b_terms(g1, -x1)], amax[j])


def solve_with_cvxopt(problem, coefs, tolerance):
    """The temporal SOCP, written from docs/temporal.md, solved by CVXOPT.

    Returns (status, T, J, seconds)."""
    K = problem["discretization"]["K"]
    ds = 1.0 / K
    m = len(coefs)
    N = m * K  # cells; piece i has grid points (i, 0..K), cell (i, k) spans (i, k) and (i, k + 1)
    lim = problem["limits"]
    vmax = np.array(lim["max_velocity"], dtype=float)
    amax = np.array(lim["max_acceleration"], dtype=float)
    lam = lim.get("max_acceleration_change")
    rho = problem["rho"]
    bnd = problem["boundary"]

    def point(i, k):
        return i * (K + 1) + k

    def tangent(i, k):
        return derivatives(coefs[i], k * ds)[0]

    # Fixed grid values: the boundary speeds (eqs. 46-47), b = |v|^2 / |f'|^2.
    fixed = {}
    for g, (i, k), key in ((point(0, 0), (0, 0), "start_velocity"), (point(m - 1, K), (m - 1, K), "end_velocity")):
        v = np.array(bnd[key], dtype=float)
        fixed[g] = float(v @ v) / float(tangent(i, k) @ tangent(i, k))
    # Joints: where the tangents turn (a kink) the vehicle stops, b = 0 on both sides; where they are
    # parallel, eq. 42 (below).
    parallel = []
    for i in range(m - 1):
        t_end, t_start = tangent(i, K), tangent(i + 1, 0)
        cross = np.linalg.norm(np.cross(t_end, t_start))
        parallel.append(cross <= 1e-9 * np.linalg.norm(t_end) * np.linalg.norm(t_start) and t_end @ t_start > 0)
        if not parallel[-1]:
            fixed[point(i, K)] = 0.0
            fixed[point(i + 1, 0)] = 0.0
    free = [g for g in range(m * (K + 1)) if g not in fixed]
    bvar = {g: i for i, g in enumerate(free)}
    nb = len(free)
    cvar = {g: nb + i for i, g in enumerate(free)}
    d0 = 2 * nb
    t_index = d0 + N
    nvar = d0 + N + (1 if rho > 0 else 0)

    rows, cols, vals, h = [], [], [], []
    eq_rows, eq_cols, eq_vals, eq_rhs = [], [], [], []

    def add_row(terms, rhs):
        r = len(h)
        for col, val in terms:
            rows.append(r)
            cols.append(col)
            vals.append(val)
        h.append(rhs)

    def b_terms(g, coef):  # coef * b_g: (terms, constant)
        if g in fixed:
            return [], coef * fixed[g]
        return [(bvar[g], coef)], 0.0

    def affine(parts):
        terms, const = [], 0.0
        for t, c in parts:
            terms += t
            const += c
        return terms, const

    def less_equal(parts, upper):  # sum(parts) <= upper as a row of G x <= h
        terms, const = affine(parts)
        if terms:
            add_row(terms, upper - const)
        elif const > upper + 1e-12:
            raise ValueError("a fixed value violates a row")

    # Eq. 42 at parallel joints: velocity continuity, b_{i+1}^0 |f'_{i+1}(0)|^2 = b_i^K |f'_i(1)|^2.
    for i in range(m - 1):
        if not parallel[i]:
            continue
        terms, const = affine([b_terms(point(i + 1, 0), float(tangent(i + 1, 0) @ tangent(i + 1, 0))),
                               b_terms(point(i, K), -float(tangent(i, K) @ tangent(i, K)))])
        r = len(eq_rhs)
        for col, val in terms:
            eq_rows.append(r)
            eq_cols.append(col)
            eq_vals.append(val)
        eq_rhs.append(-const)
    cells = [(point(i, k), point(i, k + 1), i, k) for i in range(m) for k in range(K)]
    certified = problem["constraint_mode"] == "certified"
    if certified:
        certified_rows(coefs, cells, ds, vmax, amax, b_terms, less_equal)
    else:
        # Velocity, every axis, every grid point.
        for i in range(m):
            for k in range(K + 1):
                d1 = tangent(i, k)
                for j in range(3):
                    less_equal([b_terms(point(i, k), d1[j] ** 2)], vmax[j] ** 2)
    # Axis acceleration at each cell middle as (terms, constant).
    cell_acc = []
    for g0, g1, i, k in cells:
        d1, d2 = derivatives(coefs[i], (k + 0.5) * ds)
        per_axis = []
        for j in range(3):
            per_axis.append(affine([b_terms(g1, d1[j] / (2 * ds) + 0.5 * d2[j]),
                                    b_terms(g0, -d1[j] / (2 * ds) + 0.5 * d2[j])]))
        cell_acc.append(per_axis)

    def scaled(expr, s):
        return [(c, s * v) for c, v in expr[0]], s * expr[1]

    for k in range(N if not certified else 0):
        for j in range(3):
            less_equal([cell_acc[k][j]], amax[j])
            less_equal([scaled(cell_acc[k][j], -1.0)], amax[j])
    if lam is not None:
        for j in range(3):
            for k in range(N - 1):
                diff = affine([cell_acc[k + 1][j], scaled(cell_acc[k][j], -1.0)])
                less_equal([diff], lam)
                less_equal([scaled(diff, -1.0)], lam)
            a0 = bnd["start_acceleration"][j]
            af = bnd["end_acceleration"][j]
            less_equal([cell_acc[0][j]], a0 + lam)
            less_equal([scaled(cell_acc[0][j], -1.0)], -(a0 - lam))
            less_equal([cell_acc[N - 1][j]], af + lam)
            less_equal([scaled(cell_acc[N - 1][j], -1.0)], -(af - lam))
    num_linear = len(h)

    # Second-order cones, s = h - G x, s_0 >= ||s_1..||.
    cone_dims = []
    for g in free:  # (b + 1, b - 1, 2 c): c^2 <= b
        add_row([(bvar[g], -1.0)], 1.0)
        add_row([(bvar[g], -1.0)], -1.0)
        add_row([(cvar[g], -2.0)], 0.0)
        cone_dims.append(3)

    def root_terms(g):  # sqrt(b_g)
        if g in fixed:
            return [], math.sqrt(fixed[g])
        return [(cvar[g], 1.0)], 0.0

    for k, (g0, g1, _, _) in enumerate(cells):  # (d + S, d - S, 2): d S >= 1, S = sqrt(b_0) + sqrt(b_1)
        s_terms, s_const = affine([root_terms(g0), root_terms(g1)])
        add_row([(d0 + k, -1.0)] + [(c, -v) for c, v in s_terms], s_const)
        add_row([(d0 + k, -1.0)] + [(c, v) for c, v in s_terms], -s_const)
        add_row([], 2.0)
        cone_dims.append(3)
    if rho > 0:  # (t + 1, t - 1, 2 a_0, ...): t >= sum a_k^2
        add_row([(t_index, -1.0)], 1.0)
        add_row([(t_index, -1.0)], -1.0)
        for g0, g1, _, _ in cells:
            terms, const = affine([b_terms(g1, 1.0 / (2 * ds)), b_terms(g0, -1.0 / (2 * ds))])
            add_row([(c, -2.0 * v) for c, v in terms], 2.0 * const)
        cone_dims.append(N + 2)

    cost = np.zeros(nvar)
    cost[d0:d0 + N] = 2 * ds
    if rho > 0:
        cost[t_index] = rho * ds
    G = spmatrix(vals, rows, cols, (len(h), nvar))
    solvers.options.update({"show_progress": False, "abstol": tolerance, "reltol": tolerance,
                            "feastol": tolerance, "maxiters": 200})
    start = time.perf_counter()
    dims = {"l": num_linear, "q": cone_dims, "s": []}
    if eq_rhs:
        A = spmatrix(eq_vals, eq_rows, eq_cols, (len(eq_rhs), nvar))
        sol = solvers.conelp(matrix(cost), G, matrix(h), dims, A, matrix(eq_rhs))
    else:
        sol = solvers.conelp(matrix(cost), G, matrix(h), dims)
    seconds = time.perf_counter() - start
    if sol["status"] == "primal infeasible":
        return "infeasible", None, None, seconds
    x = np.array(sol["x"]).ravel()
    b = np.array([fixed[g] if g in fixed else max(x[bvar[g]], 0.0) for g in range(m * (K + 1))])
    T = float(sum(2 * ds / (math.sqrt(b[g0]) + math.sqrt(b[g1])) for g0, g1, _, _ in cells))
    J = T + (rho * ds * float(sum(((b[g1] - b[g0]) / (2 * ds)) ** 2 for g0, g1, _, _ in cells)) if rho > 0 else 0.0)
    return sol["status"], T, J, seconds


def run_timeopt(executable, problem_path, solver, directory):
    out = os.path.join(directory, f"result_{solver}.json")
    proc = subprocess.run([executable, "temporal", problem_path, "--solver", solver, "--output", out],
                          capture_output=True, text=True, timeout=600)
    if proc.returncode == 2:
        raise RuntimeError(f"timeopt rejected the problem: {proc.stderr.strip()}")
    with open(out) as f:
        return json.load(f)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("timeopt")
    parser.add_argument("--problems", type=int, default=12)
    parser.add_argument("--seed", type=int, default=20261201)
    parser.add_argument("--keep", help="directory to keep the problem files in")
    args = parser.parse_args()
    rng = random.Random(args.seed)
    failures = 0
    not_compared = 0
    worst_t = worst_j = worst_certified = 0.0
    compared = 0
    with tempfile.TemporaryDirectory() as tmp:
        directory = args.keep or tmp
        os.makedirs(directory, exist_ok=True)
        for index in range(args.problems):
            # Every third problem in certified mode (docs/temporal.md: every Bernstein coefficient on
            # every cell within the limits).
            mode = "certified" if index % 3 == 2 else "paper"
            problem, coefs = random_problem(rng, mode)
            path = os.path.join(directory, f"problem_{index}.json")
            with open(path, "w") as f:
                json.dump(problem, f)
            # CVXOPT's own iteration can break down (a square root of a negative number) or stall
            # ("unknown") before it reaches 1e-9; the next looser tolerance is tried then (measured:
            # 1e-8 instead of 1e-9 moves T by < 1e-9 where both converge).
            status = "breakdown"
            for tolerance in (1e-9, 1e-8, 1e-7):
                try:
                    status, T, J, seconds = solve_with_cvxopt(problem, coefs, tolerance)
                except (ValueError, ArithmeticError):
                    status = "breakdown"
                if status in ("optimal", "infeasible"):
                    break
            socp = run_timeopt(args.timeopt, path, "socp", directory)
            ipopt = run_timeopt(args.timeopt, path, "ipopt", directory)
            label = (f"problem {index}: {len(coefs)} pieces, K {problem['discretization']['K']}, "
                     f"rho {problem['rho']}, lambda {problem['limits'].get('max_acceleration_change')}")
            if status not in ("optimal", "infeasible"):
                print(f"{label}: CVXOPT ended {status} at every tolerance, not compared")
                not_compared += 1
                continue
            if status != "optimal":
                agree = socp["status"] == "infeasible" and ipopt["status"] == "infeasible" and status == "infeasible"
                print(f"{label}: CVXOPT {status}, socp {socp['status']}, ipopt {ipopt['status']}"
                      f"{'' if agree else '  <-- DISAGREE'}")
                failures += 0 if agree else 1
                continue
            # With rho > 0 the objective J = T + rho sum a^2 ds is flat along directions that trade
            # T against acceleration, so a 1e-9 error in J leaves T free to ~1e-7..1e-6 in every
            # solver: J is held to 1e-6, T to the 1e-5.
            t_tolerance = TOLERANCE if problem["rho"] == 0 else 10 * TOLERANCE
            # Certified mode thins runs of nearly parallel rows by tightening their neighbours
            # (TemporalProblem::certified_thinning, 6e-4), which may raise T and J by up to half of
            # that, never lower them: the window is [-tolerance, 3e-4 + tolerance].
            thinning = CERTIFIED_THINNING_BOUND if mode == "certified" else 0.0
            line = f"{label}, {mode}: T cvxopt {T:.10f} ({seconds * 1e3:.0f} ms)"
            for name, r in (("socp", socp), ("ipopt", ipopt)):
                if r["status"] != "optimal":
                    line += f"  {name} {r['status']}  <-- DISAGREE"
                    failures += 1
                    continue
                signed_t = (r["total_time"] - T) / T
                signed_j = (r["objective"] - J) / J
                rel, rel_j = abs(signed_t), abs(signed_j)
                if mode == "paper":
                    worst_t = max(worst_t, rel)
                    worst_j = max(worst_j, rel_j)
                else:
                    worst_certified = max(worst_certified, signed_t, signed_j)
                compared += 1
                bad = (not -t_tolerance <= signed_t <= thinning + t_tolerance or
                       not -TOLERANCE <= signed_j <= thinning + TOLERANCE)
                failures += 1 if bad else 0
                line += (f"  {name} {r['total_time']:.10f} (rel {rel:.1e}, J rel {rel_j:.1e}, "
                         f"{r['solve_time_ms']:.1f} ms){'  <-- DISAGREE' if bad else ''}")
            print(line)
    print(f"{compared} comparisons; paper mode: worst relative difference in T {worst_t:.2e}, in J "
          f"{worst_j:.2e}; certified mode: largest excess of T or J {worst_certified:.2e} (thinning allows "
          f"{CERTIFIED_THINNING_BOUND:g}); {failures} failures; {not_compared} problems CVXOPT could not solve")
    if 4 * not_compared > args.problems:
        print("too few problems compared for the check to mean anything")
        return 1
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
