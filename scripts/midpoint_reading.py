#!/usr/bin/env python3
"""An independent implementation of the paper's monolithic fixed point (Problem 2, eq. 61, with
the regularisations of eq. 41 and Remark 10) on P1 elements, each term on a rule of its own.

Written from the paper (Wang et al., Comput. Mech. 71, 2023) and the errata of PAPER-NOTES
(the sign of the lambda_d term, the d_s of the Lambda_kappa test, A^T Lambda_kappa A), with
its own assembly, solver and measures. numpy only, a block-tridiagonal LU after Ruiz equilibration. It reads a
`data.csv` written by `cosserat run` (columns s_m, x_m, y_m, z_m, alpha_rad, beta_rad,
gamma_rad) and reports the iterations to a relative change, the position error and the
curvature error, the measures of docs/inverse.md.

The terms and their rules (`--rule TERM=mid|g2`, default: every term on the midpoint rule,
"the paper's scheme read with one rule"):
    stretch   the stretch-shear parts of the frozen operator (S = Q^T K Q, B S, the q3 terms)
    bending   the bending parts (Q^T J A)
    tracking  lambda_g int dx.(x - x_g)
    controls  the control costs (1/lambda_f) int xh.dxh, (1/lambda_l) int ah.dah
    lamd      the lambda_d term, d3 linearised as in (60)
    kappa     the Lambda_kappa term int d_s da . A^T Lk A d_s a
Other switches (`--lamd-data`, `--lamd-sign`) are documented in `--help`; docs/inverse.md I15
uses them to find the term whose reading makes the midpoint scheme converge or not.

Usage:
    .venv/bin/python scripts/midpoint_reading.py DATA_CSV [--lambda-d 0.3] [--max-iter 3000]
    .venv/bin/python scripts/midpoint_reading.py --history OUT/inverse_history.csv ...
(the second form reads both stopping rules off the histories of `cosserat run`, either engine).
"""
import argparse
import sys

import numpy as np

# ----------------------------------------------------------------------------- rotations (eq. 1)


def rot(a):
    """Q = Rz(alpha) Rx(beta) Ry(gamma), eq. (1), for angle arrays a[..., 3]; d_i = rows."""
    ca, sa = np.cos(a[..., 0]), np.sin(a[..., 0])
    cb, sb = np.cos(a[..., 1]), np.sin(a[..., 1])
    cg, sg = np.cos(a[..., 2]), np.sin(a[..., 2])
    z, o = np.zeros_like(ca), np.ones_like(ca)
    rz = np.stack([np.stack([ca, -sa, z], -1), np.stack([sa, ca, z], -1), np.stack([z, z, o], -1)], -2)
    rx = np.stack([np.stack([o, z, z], -1), np.stack([z, cb, -sb], -1), np.stack([z, sb, cb], -1)], -2)
    ry = np.stack([np.stack([cg, z, sg], -1), np.stack([z, o, z], -1), np.stack([-sg, z, cg], -1)], -2)
    return rz @ rx @ ry


def amat(a):
    """A(alpha) of eqs. (27)-(28): kappa^l = A d_s alpha."""
    ca, sa = np.cos(a[..., 0]), np.sin(a[..., 0])
    cb, sb = np.cos(a[..., 1]), np.sin(a[..., 1])
    z, o = np.zeros_like(ca), np.ones_like(ca)
    return np.stack([np.stack([z, -ca, sa * cb], -1), np.stack([z, -sa, -ca * cb], -1),
                     np.stack([-o, z, -sb], -1)], -2)


def d3(a):
    """d3 = (-cos b sin g, sin b, cos b cos g), Remark 3."""
    cb, sb = np.cos(a[..., 1]), np.sin(a[..., 1])
    cg, sg = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack([-cb * sg, sb, cb * cg], -1)


def dmat(a):
    """D = [0 | d_beta | d_gamma], eqs. (56)-(58)."""
    cb, sb = np.cos(a[..., 1]), np.sin(a[..., 1])
    cg, sg = np.cos(a[..., 2]), np.sin(a[..., 2])
    z = np.zeros_like(cb)
    dbeta = np.stack([sb * sg, cb, -sb * cg], -1)
    dgamma = np.stack([-cb * cg, z, -cb * sg], -1)
    return np.stack([np.stack([z, z, z], -1), dbeta, dgamma], -1)


def skew(v):
    z = np.zeros_like(v[..., 0])
    return np.stack([np.stack([z, -v[..., 2], v[..., 1]], -1), np.stack([v[..., 2], z, -v[..., 0]], -1),
                     np.stack([-v[..., 1], v[..., 0], z], -1)], -2)


# ----------------------------------------------------------------------------- rules, fields

G2 = 0.5 / np.sqrt(3.0)
RULES = {"mid": [(0.5, 1.0)], "g2": [(0.5 - G2, 0.5), (0.5 + G2, 0.5)]}
TERMS = ("stretch", "bending", "tracking", "controls", "lamd", "kappa")
# local unknowns of an element: node a (0, 1), component c (0..11) at 12 a + c; c: x 0-2, alpha 3-5,
# xhat 6-8, alphahat 9-11
FIELD = {"x": 0, "a": 3, "xh": 6, "ah": 9}


def value_op(field, xi):
    """3 x 24: the value of a field at xi in (0, 1)."""
    p = np.zeros((3, 24))
    for a, n in enumerate((1.0 - xi, xi)):
        p[:, 12 * a + FIELD[field]:12 * a + FIELD[field] + 3] = n * np.eye(3)
    return p


def deriv_op(field, h):
    """3 x 24: d_s of a field (element constant)."""
    p = np.zeros((3, 24))
    for a, dn in enumerate((-1.0 / h, 1.0 / h)):
        p[:, 12 * a + FIELD[field]:12 * a + FIELD[field] + 3] = dn * np.eye(3)
    return p


class Rod:
    """The eq. (64) rod of cases/inverse_bend.toml (circle r = L/40, E, G, k = 4/3)."""

    def __init__(self, length=1e-3, young=1.1e5, shear=5.0e4, kshear=4.0 / 3.0):
        r = length / 40.0
        area = np.pi * r * r
        inertia = np.pi * r ** 4 / 4.0
        self.length = length
        self.K = np.diag([kshear * shear * area, kshear * shear * area, young * area])
        self.J = np.diag([young * inertia, young * inertia, shear * 2.0 * inertia])


# ----------------------------------------------------------------------------- the KKT system (61)


def element_systems(u, xg, rod, w8, opt):
    """Element matrices (ne, 24, 24) and vectors (ne, 24) of eq. (61) frozen at the state u
    (nodes, 6). Rows: the test function of the same local unknown (x rows: adjoint equations,
    tested by dx; xh rows: primal equations, tested by dxh)."""
    ne = u.shape[0] - 1
    h = rod.length / ne
    m = np.zeros((ne, 24, 24))
    r = np.zeros((ne, 24))
    xa, xb = u[:-1, :3], u[1:, :3]
    aa, ab = u[:-1, 3:], u[1:, 3:]
    ga, gb = xg[:-1], xg[1:]
    dx_k = (xb - xa) / h
    da_k = (ab - aa) / h
    DX, DA, DXH, DAH = (deriv_op(f, h) for f in ("x", "a", "xh", "ah"))
    K33 = rod.K[2, 2]

    def quad(term):
        for xi, w in RULES[opt.rules[term]]:
            al = (1 - xi) * aa + xi * ab
            yield xi, w * h, al

    def add(pt, coef, pr, sym=False):
        """m += wh P_t^T coef P_r (coef: (ne, 3, 3) or a scalar)."""
        c = coef if np.ndim(coef) == 3 else coef * np.eye(3)[None]
        blk = np.einsum("ik,ekl,lj->eij", pt.T, c, pr)
        m[...] += blk
        if sym:
            m[...] += np.transpose(blk, (0, 2, 1))

    # stretch-shear: primal  d_s dxh.S d_s x - dah.B S d_s x = K33 d_s dxh.q3 - K33 dah.B q3, and its transpose
    for xi, wh, al in quad("stretch"):
        Q = rot(al)
        S = np.transpose(Q, (0, 2, 1)) @ rod.K @ Q
        B = skew(dx_k)
        q3 = Q[:, 2, :]
        add(DXH, wh * S, DX, sym=True)
        AH = value_op("ah", xi)
        add(AH, -wh * (B @ S), DX, sym=True)
        r += wh * K33 * (np.einsum("ik,ek->ei", DXH.T, q3) - np.einsum("ik,ek->ei", AH.T, np.einsum("ekl,el->ek", B, q3)))
    # bending: primal d_s dah.(Q^T J A) d_s a, and its transpose
    for xi, wh, al in quad("bending"):
        Q, A = rot(al), amat(al)
        C = np.transpose(Q, (0, 2, 1)) @ rod.J @ A
        add(DAH, wh * C, DA, sym=True)
    # tracking lambda_g int dx.(x - x_g)
    for xi, wh, al in quad("tracking"):
        X = value_op("x", xi)
        add(X, wh * w8["g"], X)
        xgq = (1 - xi) * ga + xi * gb
        r += wh * w8["g"] * np.einsum("ik,ek->ei", X.T, xgq)
    # control costs -(1/lf) int xh.dxh - (1/ll) int ah.dah (f = xh/lf, l = ah/ll, eq. 54)
    for xi, wh, al in quad("controls"):
        XH, AH = value_op("xh", xi), value_op("ah", xi)
        add(XH, -wh / w8["f"], XH)
        add(AH, -wh / w8["l"], AH)
    # lambda_d: (d_s dx - D dalpha).(d_s x - D alpha - (d3_k - D alpha_k)), corrected sign (PAPER-NOTES)
    for xi, wh, al in quad("lamd"):
        al_d = al if opt.lamd_data == "point" else 0.5 * (aa + ab)
        D = dmat(al_d)
        c = d3(al_d) - np.einsum("ekl,el->ek", D, al if opt.lamd_data == "point" else al_d)
        AL = value_op("a", xi)
        # test/trial operator T = DX - D AL, per element (ne, 3, 24)
        T = DX[None] - np.einsum("ekl,lj->ekj", D, AL)
        sg = 1.0 if opt.lamd_sign == "corrected" else -1.0
        # printed sign: the alpha test enters with +D: T_test = DX + D AL
        Tt = DX[None] - sg * np.einsum("ekl,lj->ekj", D, AL)
        m[...] += wh * w8["d"] * np.einsum("eki,ekj->eij", Tt, T)
        r += wh * w8["d"] * np.einsum("eki,ek->ei", Tt, c)
    # Lambda_kappa: int d_s dalpha . A_k^T Lk A_k d_s alpha
    if np.max(w8["k"]) > 0:
        for xi, wh, al in quad("kappa"):
            A = amat(al)
            Kk = np.transpose(A, (0, 2, 1)) @ np.diag(w8["k"]) @ A
            add(DA, wh * Kk, DA)
    return m, r


def assemble(m, r):
    """The global matrix as a block-tridiagonal one (12 x 12 blocks, one per node): diagonal
    blocks dg[i], upper up[i] = (i, i + 1), lower lo[i] = (i + 1, i); and the right-hand side."""
    ne = m.shape[0]
    dg = np.zeros((ne + 1, 12, 12))
    dg[:-1] += m[:, :12, :12]
    dg[1:] += m[:, 12:, 12:]
    up = m[:, :12, 12:].copy()
    lo = m[:, 12:, :12].copy()
    rhs = np.zeros((ne + 1, 12))
    rhs[:-1] += r[:, :12]
    rhs[1:] += r[:, 12:]
    return [dg, up, lo], rhs


def dirichlet(sysm, rhs, xg):
    """I5 / Remark 6: x = x_g at both ends, xh = ah = 0 at both ends, alpha_1(0) = 0; each row
    replaced by the identity row."""
    dg, up, lo = sysm
    last = xg.shape[0] - 1
    fixed = []
    for node in (0, last):
        fixed += [(node, c, xg[node, c]) for c in range(3)]
        fixed += [(node, c, 0.0) for c in range(6, 12)]
    fixed.append((0, 3, 0.0))
    for node, c, v in fixed:
        dg[node, c, :] = 0.0
        dg[node, c, c] = 1.0
        if node < last:
            up[node, c, :] = 0.0
        if node > 0:
            lo[node - 1, c, :] = 0.0
        rhs[node, c] = v


def ruiz_solve(sysm, b, passes=5):
    """Five passes of Ruiz equilibration (row and column maxima to 1), then block LU of the
    block-tridiagonal matrix (partial pivoting inside each diagonal block)."""
    dg, up, lo = (a.copy() for a in sysm)
    n = dg.shape[0]
    dr, dc = np.ones((n, 12)), np.ones((n, 12))
    for _ in range(passes):
        rmax = np.abs(dg).max(axis=2)
        rmax[:-1] = np.maximum(rmax[:-1], np.abs(up).max(axis=2))
        rmax[1:] = np.maximum(rmax[1:], np.abs(lo).max(axis=2))
        cmax = np.abs(dg).max(axis=1)
        cmax[1:] = np.maximum(cmax[1:], np.abs(up).max(axis=1))
        cmax[:-1] = np.maximum(cmax[:-1], np.abs(lo).max(axis=1))
        rr, cc = np.sqrt(rmax), np.sqrt(cmax)
        rr[rr == 0] = 1.0
        cc[cc == 0] = 1.0
        dg /= rr[:, :, None] * cc[:, None, :]
        up /= rr[:-1, :, None] * cc[1:, None, :]
        lo /= rr[1:, :, None] * cc[:-1, None, :]
        dr /= rr
        dc /= cc
    y = dr * b
    # forward elimination: dg[i] <- dg[i] - lo[i-1] dg[i-1]^-1 up[i-1]
    for i in range(1, n):
        f = np.linalg.solve(dg[i - 1].T, lo[i - 1].T).T  # lo[i-1] dg[i-1]^-1
        dg[i] -= f @ up[i - 1]
        y[i] -= f @ y[i - 1]
    x = np.zeros_like(y)
    x[-1] = np.linalg.solve(dg[-1], y[-1])
    for i in range(n - 2, -1, -1):
        x[i] = np.linalg.solve(dg[i], y[i] - up[i] @ x[i + 1])
    return dc * x


# ----------------------------------------------------------------------------- measures


def relative_change(new, old):
    def ratio(d, n):
        return 0.0 if d == 0.0 else d / n
    return max(ratio(np.linalg.norm(new[:, :3] - old[:, :3]), np.linalg.norm(new[:, :3])),
               ratio(np.linalg.norm(new[:, 3:] - old[:, 3:]), np.linalg.norm(new[:, 3:])))


def curvatures(alpha, h):
    mid = 0.5 * (alpha[:-1] + alpha[1:])
    return np.einsum("ekl,el->ek", amat(mid), (alpha[1:] - alpha[:-1]) / h)


def rel_err(a, b, skip=0):
    n = len(a)
    sl = slice(skip, n - skip)
    return np.sqrt(np.sum((a[sl] - b[sl]) ** 2) / np.sum(b[sl] ** 2))


def x_error(x, xg, rule):
    """||x - x_g|| / ||x_g|| on the rule (g2: exact for P1)."""
    e2 = g2 = 0.0
    for xi, w in RULES[rule]:
        d = (1 - xi) * (x[:-1] - xg[:-1]) + xi * (x[1:] - xg[1:])
        g = (1 - xi) * xg[:-1] + xi * xg[1:]
        e2 += w * np.sum(d * d)
        g2 += w * np.sum(g * g)
    return np.sqrt(e2 / g2)


# ----------------------------------------------------------------------------- the fixed point


def solve(data, rod, w8, opt, log=None):
    s, xg, truth = data[:, 0], data[:, 1:4], data[:, 4:7]
    nn = len(s)
    h = rod.length / (nn - 1)
    u = np.zeros((nn, 6))
    u[:, 2] = s  # the straight reference state
    kappa_true = curvatures(truth, h)
    within = 0
    first_dip = None
    rec = None
    for k in range(1, opt.max_iter + 1):
        m, r = element_systems(u, xg, rod, w8, opt)
        sysm, rhs = assemble(m, r)
        dirichlet(sysm, rhs, xg)
        sol = ruiz_solve(sysm, rhs)
        new = opt.relaxation * sol[:, :6] + (1 - opt.relaxation) * u
        ch = relative_change(new, u)
        u = new
        if not np.all(np.isfinite(u)):
            return dict(iterations=k, status="non-finite", change=ch)
        within = within + 1 if ch <= opt.tol else 0
        kap = curvatures(u[:, 3:], h)
        rec = dict(iterations=k, change=ch, x_err=x_error(u[:, :3], xg, "g2"), x_err_mid=x_error(u[:, :3], xg, "mid"),
                   kappa_err=rel_err(kap, kappa_true), kappa_err_inner=rel_err(kap, kappa_true, 5))
        if log and (k % opt.every == 0 or k == 1):
            log(rec)
        if first_dip is None and ch <= opt.tol:
            first_dip = dict(rec)
        if within >= opt.plateau:
            rec["status"] = "converged"
            rec["first_dip"] = first_dip
            return rec
    rec["status"] = "not converged"
    rec["first_dip"] = first_dip
    return rec


def summarise(path, tol, plateau):
    """Both stopping rules read off an `inverse_history.csv` of `cosserat run` (either engine):
    the first iteration whose relative change is <= tol ("first dip"), the first with `plateau`
    consecutive ones (D5), and the largest change in the 400 iterations after the first dip."""
    rows = np.genfromtxt(path, delimiter=",", names=True)
    ch = np.atleast_1d(rows["rel_change"])
    below = np.flatnonzero(ch <= tol)
    out = [f"{path}: {len(ch)} iterations, last change {ch[-1]:.2e}"]
    if len(below):
        k = below[0]
        kap = rows["kappa_err_rel"][k] if "kappa_err_rel" in rows.dtype.names else float("nan")
        out.append(f"first change <= {tol:g} at {k + 1} (x error {rows['x_err_rel'][k]:.3g}, kappa error {kap:.3g}),"
                   f" largest change in the next 400: {ch[k + 1:k + 401].max(initial=0):.2e}")
    run = 0
    for k, c in enumerate(ch):
        run = run + 1 if c <= tol else 0
        if run == plateau:
            out.append(f"{plateau} consecutive at {k + 1}")
            break
    print("; ".join(out))


def main(argv=None):
    if argv is None:
        argv = sys.argv[1:]
    if argv[:1] == ["--history"]:
        for path in argv[1:]:
            summarise(path, 3e-6, 5)
        return
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("data", help="data.csv of `cosserat run` on the inverse case")
    ap.add_argument("--lambda-g", type=float, default=1e9)
    ap.add_argument("--lambda-f", type=float, default=1.0)
    ap.add_argument("--lambda-l", type=float, default=1e-10)
    ap.add_argument("--lambda-d", type=float, default=1e-6)
    ap.add_argument("--lambda-kappa", type=float, nargs=3, default=[0.0, 0.0, 1e-10])
    ap.add_argument("--relaxation", type=float, default=0.5)
    ap.add_argument("--tol", type=float, default=3e-6)
    ap.add_argument("--plateau", type=int, default=5, help="consecutive changes within tol to stop (D5)")
    ap.add_argument("--max-iter", type=int, default=3000)
    ap.add_argument("--every", type=int, default=100, help="print a record every N iterations (with -v)")
    ap.add_argument("--rule", action="append", default=[], metavar="TERM=mid|g2",
                    help="the rule of one term (default mid for all): " + ", ".join(TERMS))
    ap.add_argument("--all", choices=sorted(RULES), default="mid", help="the rule of every term not named by --rule")
    ap.add_argument("--lamd-data", choices=["point", "mean"], default="point",
                    help="where D and d3 of the lambda_d term are taken: at the rule's point (the scheme) or at the element mean")
    ap.add_argument("--lamd-sign", choices=["corrected", "printed"], default="corrected",
                    help="the sign of the alpha variation of the lambda_d term (PAPER-NOTES erratum)")
    ap.add_argument("-v", "--verbose", action="store_true")
    opt = ap.parse_args(argv)
    opt.rules = {t: opt.all for t in TERMS}
    for item in opt.rule:
        t, _, v = item.partition("=")
        if t not in TERMS or v not in RULES:
            ap.error(f"--rule {item}: TERM one of {TERMS}, rule mid or g2")
        opt.rules[t] = v
    data = np.loadtxt(opt.data, delimiter=",", skiprows=1)
    w8 = dict(g=opt.lambda_g, f=opt.lambda_f, l=opt.lambda_l, d=opt.lambda_d, k=np.array(opt.lambda_kappa))
    log = (lambda rec: print(rec, file=sys.stderr, flush=True)) if opt.verbose else None
    rec = solve(data, Rod(), w8, opt, log)
    fd = rec.pop("first_dip", None)
    print(" ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}" for k, v in rec.items()))
    if fd:
        print("first change within tol: " + " ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}"
                                                        for k, v in fd.items()))


if __name__ == "__main__":
    main()
