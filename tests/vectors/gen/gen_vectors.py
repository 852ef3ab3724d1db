#!/usr/bin/env python3
# Test-vector generator for raylane (ray-sphere, ray-plane, ray-triangle in f32 lanes).
#
# Rerun from the repository root:
#
#     python3 tests/vectors/gen/gen_vectors.py
#
# It (re)writes every tests/vectors/*.txt file (the parent directory of this
# script's directory) and prints a summary.  Needs Python 3 and mpmath (>= 1.0).
# The output is deterministic: every file has its own seeded random.Random
# stream, inputs are produced with plain IEEE double arithmetic (+ - * / sqrt,
# all correctly rounded) and mpmath; no platform libm function is used.
#
# Reference semantics, line grammar and filters: see README.md next to this file.
"""Generate the raylane test vectors (see README.md)."""

import math
import os
import random
import struct
import time
from decimal import Decimal
from fractions import Fraction as F

from mpmath import mp, mpf

mp.dps = 80

BASE_SEED = 20250311
SEEDS = {  # one independent random.Random stream per file
    "sphere_random.txt": BASE_SEED + 1,
    "sphere_far.txt": BASE_SEED + 2,
    "sphere_ground.txt": BASE_SEED + 3,
    "sphere_special.txt": BASE_SEED + 4,
    "plane_random.txt": BASE_SEED + 5,
    "triangle_random.txt": BASE_SEED + 6,
    "triangle_special.txt": BASE_SEED + 7,
    "triangle_far.txt": BASE_SEED + 11,
    "triangle_needle.txt": BASE_SEED + 12,
    "triangle_grazing.txt": BASE_SEED + 13,
    "triangle_offset.txt": BASE_SEED + 14,
    "triangle_grid.txt": BASE_SEED + 15,
    "sphere_grazing.txt": BASE_SEED + 16,
    "sphere_offset.txt": BASE_SEED + 17,
    "sphere_tiny.txt": BASE_SEED + 18,
    "sphere_huge.txt": BASE_SEED + 19,
    "plane_grazing.txt": BASE_SEED + 20,
    "plane_offset.txt": BASE_SEED + 21,
    "sphere_far_low_k": BASE_SEED + 22,  # sphere_far.txt's blocks k = 4, 5 (added later)
    "robustness_check": BASE_SEED + 99,  # Monte-Carlo double check of filter (a)
}

HERE = os.path.dirname(os.path.abspath(__file__))
OUT_DIR = os.path.dirname(HERE)
RERUN = "python3 tests/vectors/gen/gen_vectors.py"

DECIDE_FACTOR = F(3, 2)     # filter (a): |q| > 1.5 * band
COND_REL = mpf("2e-6")      # filter (b): t sensitivity <= 2e-6 |t|
COND_ABS = mpf("2e-6")      # filter (b): u, v sensitivity <= 2e-6
ULP_STEPS = 2               # perturbation size, in f32 ulps, for both filters
MC_TRIALS = 16              # random 2-ulp perturbations re-classified per kept case

# ---------------------------------------------------------------------------
# f32 helpers
# ---------------------------------------------------------------------------

INF = float("inf")
NAN = float("nan")


def f32(x):
    """Round a double to the nearest f32 (IEEE round-to-nearest-even)."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def bits32(x):
    return struct.unpack("<I", struct.pack("<f", x))[0]


def from_bits32(b):
    return struct.unpack("<f", struct.pack("<I", b))[0]


def pow2(e):
    return F(2 ** e) if e >= 0 else F(1, 2 ** (-e))


def ulp32(x):
    """Spacing of f32 numbers at |x| (upper side at powers of 2); 2^-149 at 0."""
    x = abs(x)
    if x < 2.0 ** -126:
        return pow2(-149)
    m, e = math.frexp(x)          # x = m 2^e, 0.5 <= m < 1
    return pow2(e - 24)


def round32(q):
    """Exact rational -> nearest f32 (ties to even), as a Python float."""
    if q == 0:
        return 0.0
    neg = q < 0
    q = -q if neg else q
    n, d = q.numerator, q.denominator
    e = n.bit_length() - d.bit_length()
    # fix e so that 2^e <= q < 2^(e+1)
    if (n << max(0, -e)) < (d << max(0, e)):
        e -= 1
    e = max(e, -126)
    sh = 23 - e
    num, den = (n << sh, d) if sh >= 0 else (n, d << (-sh))
    m, rem = divmod(num, den)
    if 2 * rem > den or (2 * rem == den and (m & 1)):
        m += 1
    if e > 127 or (e == 127 and m >= 2 ** 24):
        v = INF
    else:
        v = math.ldexp(m, e - 23)
    return -v if neg else v


def next32(y):
    """Next f32 above a positive finite f32."""
    return from_bits32(bits32(y) + 1)


def prev32(y):
    return from_bits32(bits32(y) - 1)


def step32(x, k):
    """Move the f32 x by k ulps (k may be negative); ordered through zero."""
    b = bits32(x)
    o = b if b < 0x80000000 else -(b - 0x80000000)
    o += k
    b = o if o >= 0 else 0x80000000 + (-o)
    b = min(b, 0x7F800000) if o >= 0 else min(b, 0xFF800000)
    return from_bits32(b)


def dec_to_f32_exact(s):
    """Correctly rounded decimal string -> f32 (what Rust's parse::<f32> does)."""
    return round32(F(Decimal(s)))


def fmt32(x):
    """Shortest decimal that round-trips to the f32 value x."""
    if math.isnan(x):
        return "NaN"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    assert f32(x) == x, x
    if x == 0:
        return "-0" if math.copysign(1.0, x) < 0 else "0"
    for p in range(1, 10):
        s = "%.*g" % (p, x)
        if f32(float(s)) == x:
            break
    else:
        raise AssertionError(x)
    # normalise the %g spelling: no '+', no leading exponent zeros, positional
    # notation for moderate magnitudes (10000 rather than 1e+04)
    neg = s.startswith("-")
    t = s.lstrip("-")
    mant, _, ex = t.partition("e")
    ex = int(ex) if ex else 0
    ip, _, fp = mant.partition(".")
    digits = (ip + fp).lstrip("0")
    lead_zeros = len(ip + fp) - len((ip + fp).lstrip("0"))
    exp10 = ex + len(ip) - 1 - lead_zeros   # decimal exponent of first digit
    digits = digits.rstrip("0") or "0"
    if -5 <= exp10 < 9:
        pp = exp10 + 1
        if pp <= 0:
            out = "0." + "0" * (-pp) + digits
        elif pp >= len(digits):
            out = digits + "0" * (pp - len(digits))
        else:
            out = digits[:pp] + "." + digits[pp:]
    else:
        out = digits[0] + ("." + digits[1:] if len(digits) > 1 else "") + "e" + str(exp10)
    out = ("-" if neg else "") + out
    assert dec_to_f32_exact(out) == x, (x, out)   # exact (no double rounding)
    assert f32(float(out)) == x, (x, out)
    return out


def fr2mp(q):
    return mpf(q.numerator) / q.denominator


def mp2fr(x):
    sign, man, exp, _bc = x._mpf_
    v = F(man) * pow2(exp)
    return -v if sign else v


def round32_by_cmp(cmp, guess):
    """Nearest f32 (ties to even) to a positive real t known only through
    cmp(m) = sign(t - m) for rational m (exact).  guess: approximate float."""
    y = f32(guess)
    assert 0 < y < INF
    for _ in range(64):
        lo = (F(prev32(y)) + F(y)) / 2
        hi = (F(y) + F(next32(y))) / 2
        sl = cmp(lo)
        if sl < 0:
            y = prev32(y)
            continue
        sh = cmp(hi)
        if sh > 0:
            y = next32(y)
            continue
        if sl == 0:
            return y if bits32(y) % 2 == 0 else prev32(y)
        if sh == 0:
            return y if bits32(y) % 2 == 0 else next32(y)
        return y
    raise AssertionError("rounding did not converge")


def sgn(q):
    return (q > 0) - (q < 0)


# ---------------------------------------------------------------------------
# deterministic random helpers (double arithmetic; mpmath for exp/log/trig)
# ---------------------------------------------------------------------------

def loguniform(rng, lo, hi):
    u = rng.random()
    return float(mp.exp(mp.log(lo) + u * (mp.log(hi) - mp.log(lo))))


def rand_unit(rng):
    while True:
        v = (rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1))
        n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
        if 1e-3 < n2 <= 1.0:
            n = math.sqrt(n2)
            return (v[0] / n, v[1] / n, v[2] / n)


def vadd(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def vsub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def vscale(s, a):
    return (s * a[0], s * a[1], s * a[2])


def vdot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def vcross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def vnorm(a):
    return math.sqrt(vdot(a, a))


def vunit(a):
    n = vnorm(a)
    return (a[0] / n, a[1] / n, a[2] / n)


def rand_perp(rng, d):
    """Random unit vector perpendicular to the (unit-ish) vector d."""
    while True:
        e = vcross(d, rand_unit(rng))
        if vnorm(e) > 0.1:
            e = vunit(e)
            # one Gram-Schmidt pass against d for good measure
            dn = vunit(d)
            e = vunit(vsub(e, vscale(vdot(e, dn), dn)))
            return e


def rand_box(rng, h):
    return (rng.uniform(-h, h), rng.uniform(-h, h), rng.uniform(-h, h))


def v32(a):
    return tuple(f32(x) for x in a)


def dir32(rng, v, unit):
    """f32 direction along v: unit (normalised then rounded) or of random
    length in [0.01, 100] (log-uniform)."""
    u = vunit(v)
    if not unit:
        u = vscale(loguniform(rng, 0.01, 100.0), u)
    return v32(u)


# ---------------------------------------------------------------------------
# exact gradients of polynomial decision quantities
# ---------------------------------------------------------------------------

def grad_exact(fn, v):
    """Exact gradient of every quantity returned by fn at the rational point v.
    fn's quantities are polynomials of degree <= 2 in each single variable, so
    the central difference with step 1 is exact."""
    g = None
    for i in range(len(v)):
        vp = list(v)
        vm = list(v)
        vp[i] += 1
        vm[i] -= 1
        qp, qm = fn(vp), fn(vm)
        if g is None:
            g = [[None] * len(v) for _ in qp]
        for j in range(len(qp)):
            g[j][i] = (qp[j] - qm[j]) / 2
    return g


def ulp_weights(xs):
    return [ULP_STEPS * ulp32(x) for x in xs]


def band(gq, w):
    return sum(abs(gi) * wi for gi, wi in zip(gq, w))


def decidable(q, gq, w):
    return abs(q) > DECIDE_FACTOR * band(gq, w)


# ---------------------------------------------------------------------------
# exact reference: sphere
# ---------------------------------------------------------------------------

class Result:
    def __init__(self, kind, xs):
        self.kind = kind
        self.xs = list(xs)
        self.flag = None      # reason for a structural miss / excluded situation
        self.out = []         # f32 outputs (empty = miss)
        self.exact = []       # high-precision values of the outputs (mpf)
        self.dec = []         # indices of the decision quantities that matter
        self.record = False   # write the conditioning after `~` (see cond_values)

    @property
    def hit(self):
        return bool(self.out)


def sph_quant(v):
    ox, oy, oz, dx, dy, dz, cx, cy, cz, r = v
    wx, wy, wz = ox - cx, oy - cy, oz - cz
    a = dx * dx + dy * dy + dz * dz
    b = dx * wx + dy * wy + dz * wz
    c = wx * wx + wy * wy + wz * wz - r * r
    return (a, b, c, b * b - a * c)


SPH_QNAMES = ("a", "b'", "c'", "D")


def sphere_eval(xs):
    res = Result("sphere", xs)
    if not all(math.isfinite(x) for x in xs):
        res.flag = "non-finite input"
        return res
    v = [F(x) for x in xs]
    res.v = v
    if v[3] == 0 and v[4] == 0 and v[5] == 0:
        res.flag = "zero direction"
        return res
    if not v[9] > 0:
        res.flag = "radius <= 0"
        return res
    a, b, c, D = q = sph_quant(v)
    res.q = q
    sig = []
    if D < 0:
        res.dec = [3]
    elif D == 0:
        res.flag = "tangent (D = 0)"
        return res
    elif c < 0:
        res.dec = [3, 2]
        sig = [+1]
    elif c == 0:
        res.flag = "origin on the surface (c' = 0)"
        return res
    else:
        res.dec = [3, 2, 1]
        sig = [-1, +1] if b < 0 else []
    res.sig = sig
    if not sig:
        return res
    s = mp.sqrt(fr2mp(D))
    am, bm, cm = fr2mp(a), fr2mp(b), fr2mp(c)
    res.s = s
    tplus = (-bm + s) / am
    for sg in sig:
        t = tplus if sg > 0 else cm / (am * tplus)   # product of the roots = c'/a

        def cmp(m, sg=sg):
            # sign(t - m), t = (-b + sg sqrt(D)) / a, a > 0
            qq = m * a + b
            if sg > 0:      # sqrt(D) vs qq
                if qq < 0:
                    return 1
                return sgn(D - qq * qq)
            else:           # -sqrt(D) vs qq  <=>  sqrt(D) vs -qq (reversed)
                if qq >= 0:
                    return -1
                return sgn(qq * qq - D)

        res.exact.append(t)
        res.out.append(round32_by_cmp(cmp, float(t)))
    return res


def sphere_sens(res, xs_cond=None):
    """2-ulp first-order sensitivities of the listed roots (absolute, mpf).
    xs_cond: alternative (translated) inputs on which to measure them."""
    v = res.v if xs_cond is None else [F(x) for x in xs_cond]
    if xs_cond is not None:
        assert sph_quant(v) == res.q
    g = grad_exact(sph_quant, v)
    w = ulp_weights(xs_cond if xs_cond is not None else res.xs)
    a, b, c, D = (fr2mp(x) for x in res.q)
    out = []
    for sg, t in zip(res.sig, res.exact):
        tot = mpf(0)
        for i in range(len(v)):
            ga, gb, gD = fr2mp(g[0][i]), fr2mp(g[1][i]), fr2mp(g[3][i])
            dt = (-gb + sg * gD / (2 * res.s)) / a - t * ga / a
            tot += abs(dt) * fr2mp(w[i])
        out.append(tot)
    return out


def sphere_decide(res):
    g = grad_exact(sph_quant, res.v)
    w = ulp_weights(res.xs)
    bad = [SPH_QNAMES[j] for j in res.dec if not decidable(res.q[j], g[j], w)]
    return bad


def sphere_signature(xs):
    return len(sphere_eval(xs).out)


# ---------------------------------------------------------------------------
# exact reference: plane
# ---------------------------------------------------------------------------

def pl_quant(v):
    ox, oy, oz, dx, dy, dz, px, py, pz, nx, ny, nz = v
    den = dx * nx + dy * ny + dz * nz
    num = (px - ox) * nx + (py - oy) * ny + (pz - oz) * nz
    return (den, num)


PL_QNAMES = ("d.n", "(p-o).n")


def plane_eval(xs):
    res = Result("plane", xs)
    if not all(math.isfinite(x) for x in xs):
        res.flag = "non-finite input"
        return res
    v = [F(x) for x in xs]
    res.v = v
    if v[3] == 0 and v[4] == 0 and v[5] == 0:
        res.flag = "zero direction"
        return res
    if v[9] == 0 and v[10] == 0 and v[11] == 0:
        res.flag = "zero normal"
        return res
    den, num = res.q = pl_quant(v)
    if den == 0:
        res.flag = "parallel (d.n = 0)" if num != 0 else "ray in the plane (d.n = 0, (p-o).n = 0)"
        return res
    res.dec = [0, 1]
    if num == 0:
        res.flag = "origin on the plane (t = 0)"
        return res
    t = num / den
    res.rat = [t]
    if t > 0:
        res.exact = [fr2mp(t)]
        res.out = [round32(t)]
    return res


def rat_sens(res, fn, k_den, k_nums, xs_cond=None):
    """Sensitivities of the quotients q[k_num]/q[k_den] (exact Fractions)."""
    v = res.v if xs_cond is None else [F(x) for x in xs_cond]
    q = fn(v)
    if xs_cond is not None:
        assert q == res.q
    g = grad_exact(fn, v)
    w = ulp_weights(xs_cond if xs_cond is not None else res.xs)
    den = q[k_den]
    out = []
    for k in k_nums:
        tot = F(0)
        for i in range(len(v)):
            dq = (g[k][i] * den - q[k] * g[k_den][i]) / (den * den)
            tot += abs(dq) * w[i]
        out.append(fr2mp(tot))
    return out


def plane_decide(res):
    g = grad_exact(pl_quant, res.v)
    w = ulp_weights(res.xs)
    return [PL_QNAMES[j] for j in res.dec if not decidable(res.q[j], g[j], w)]


def plane_signature(xs):
    return len(plane_eval(xs).out)


# ---------------------------------------------------------------------------
# exact reference: triangle
# ---------------------------------------------------------------------------

def tri_quant(v):
    ox, oy, oz, dx, dy, dz, ax, ay, az, bx, by, bz, cx, cy, cz = v
    e1 = (bx - ax, by - ay, bz - az)
    e2 = (cx - ax, cy - ay, cz - az)
    s = (ox - ax, oy - ay, oz - az)
    d = (dx, dy, dz)
    p = (d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0])
    det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2]
    unum = s[0] * p[0] + s[1] * p[1] + s[2] * p[2]
    qv = (s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0])
    vnum = d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]
    tnum = e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]
    return (det, unum, vnum, det - unum - vnum, tnum)


TRI_QNAMES = ("det", "u-num", "v-num", "(1-u-v)-num", "t-num")


def tri_area_zero(v):
    ax, ay, az, bx, by, bz, cx, cy, cz = v[6:15]
    e1 = (bx - ax, by - ay, bz - az)
    e2 = (cx - ax, cy - ay, cz - az)
    n = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
    return n == (0, 0, 0)


def triangle_eval(xs):
    res = Result("triangle", xs)
    if not all(math.isfinite(x) for x in xs):
        res.flag = "non-finite input"
        return res
    v = [F(x) for x in xs]
    res.v = v
    if v[3] == 0 and v[4] == 0 and v[5] == 0:
        res.flag = "zero direction"
        return res
    if tri_area_zero(v):
        res.flag = "degenerate triangle (zero area)"
        return res
    det, unum, vnum, wnum, tnum = res.q = tri_quant(v)
    if det == 0:
        res.flag = "ray parallel to the triangle plane (det = 0)"
        return res
    res.dec = [0, 1, 2, 3, 4]
    if tnum == 0:
        res.flag = "origin in the triangle's plane (t = 0)"
        return res
    t, u, vv, ww = tnum / det, unum / det, vnum / det, wnum / det
    res.rat = [t, u, vv]
    res.front = det > 0     # MT det = e1.(d x e2) = -d.((b-a)x(c-a)) > 0: ray against the normal
    if t > 0 and u >= 0 and vv >= 0 and ww >= 0:
        res.exact = [fr2mp(t), fr2mp(u), fr2mp(vv)]
        res.out = [round32(t), round32(u), round32(vv)]
    return res


def triangle_decide(res):
    g = grad_exact(tri_quant, res.v)
    w = ulp_weights(res.xs)
    return [TRI_QNAMES[j] for j in res.dec if not decidable(res.q[j], g[j], w)]


def triangle_signature(xs):
    return len(triangle_eval(xs).out)


# ---------------------------------------------------------------------------
# filters
# ---------------------------------------------------------------------------

EVAL = {"sphere": sphere_eval, "plane": plane_eval, "triangle": triangle_eval}
SIGN = {"sphere": sphere_signature, "plane": plane_signature, "triangle": triangle_signature}

MC_RNG = random.Random(SEEDS["robustness_check"])


def mc_robust(kind, xs, trials=MC_TRIALS):
    """Re-classify (number of roots / hit or miss) under random perturbations
    of every input by -2..2 ulps."""
    ref = SIGN[kind](xs)
    for _ in range(trials):
        ys = [step32(x, MC_RNG.randint(-ULP_STEPS, ULP_STEPS)) for x in xs]
        if SIGN[kind](ys) != ref:
            return False
    return True


def translated(kind, xs):
    """Inputs translated so that the sphere centre / triangle vertex a is at the
    origin (plane: p at the origin), if all the differences are exact f32."""
    if kind == "sphere":
        shift = xs[6:9]
        idx = [0, 1, 2, 6, 7, 8]
    elif kind == "plane":
        shift = xs[6:9]
        idx = [0, 1, 2, 6, 7, 8]
    else:
        shift = xs[6:9]
        idx = [0, 1, 2, 6, 7, 8, 9, 10, 11, 12, 13, 14]
    ys = list(xs)
    for i in idx:
        j = i % 3
        dv = F(xs[i]) - F(shift[j])
        y = round32(dv)
        if F(y) != dv:
            raise ValueError("translation is not exact in f32")
        ys[i] = y
    return ys


class Stats:
    def __init__(self):
        self.tried = 0
        self.kept = 0
        self.rej = {}

    def reject(self, why):
        self.rej[why] = self.rej.get(why, 0) + 1

    def __str__(self):
        r = ", ".join("%s %d" % kv for kv in sorted(self.rej.items()))
        return "%d tried, %d kept%s" % (self.tried, self.kept, (" (rejected: " + r + ")") if r else "")


def accept(kind, xs, stats=None, cond="raw"):
    """Evaluate and filter one generated case.  cond: 'raw' (filter (b) on the
    inputs as given), 'translated' (filter (b) on the exactly translated inputs),
    'report' (no filter (b); sensitivities are only recorded), 'report-translated'
    (no filter (b); sensitivities recorded on the exactly translated inputs).
    Returns the Result (with .sens) or None."""
    if stats is not None:
        stats.tried += 1
    xs = [f32(x) for x in xs]
    res = EVAL[kind](xs)

    def rej(why):
        if stats is not None:
            stats.reject(why)
        return None

    if res.flag is not None:
        return rej(res.flag)
    dec = {"sphere": sphere_decide, "plane": plane_decide, "triangle": triangle_decide}[kind]
    bad = dec(res)
    if bad:
        return rej("(a) undecidable " + "/".join(bad))
    if res.hit:
        xs_c = translated(kind, xs) if cond.endswith("translated") else None
        if kind == "sphere":
            sens = sphere_sens(res, xs_c)
        elif kind == "plane":
            sens = rat_sens(res, pl_quant, 0, [1], xs_c)
        else:
            sens = rat_sens(res, tri_quant, 0, [4, 1, 2], xs_c)
        res.sens = sens
        res.relsens = [sens[0] / abs(res.exact[0])] if kind != "sphere" else [s / abs(t) for s, t in zip(sens, res.exact)]
        if not cond.startswith("report"):
            if kind == "sphere":
                if any(s > COND_REL * abs(t) for s, t in zip(sens, res.exact)):
                    return rej("(b) ill-conditioned t")
            else:
                if sens[0] > COND_REL * abs(res.exact[0]):
                    return rej("(b) ill-conditioned t")
                if kind == "triangle" and (sens[1] > COND_ABS or sens[2] > COND_ABS):
                    return rej("(b) ill-conditioned u/v")
    if not mc_robust(kind, xs):
        return rej("(a') Monte-Carlo 2-ulp re-classification differs")
    if stats is not None:
        stats.kept += 1
    return res


# ---------------------------------------------------------------------------
# output
# ---------------------------------------------------------------------------

GRAMMAR = {
    "sphere": "sphere   ox oy oz  dx dy dz  cx cy cz  r  -> miss | t0 [t1]",
    "plane": "plane    ox oy oz  dx dy dz  px py pz  nx ny nz  -> miss | t",
    "triangle": "triangle ox oy oz  dx dy dz  ax ay az  bx by bz  cx cy cz  -> miss | t u v",
}

SEMANTICS = {
    "sphere": [
        "Reference: roots of |o + t d - c|^2 = r^2 in the open interval t in (0, inf), ascending;",
        "  origin strictly inside -> only the exit root; non-finite input, zero d, r <= 0 or NaN -> miss.",
        "  a = d.d, b' = d.(o-c), c' = |o-c|^2 - r^2, D = b'^2 - a c'; hits decided exactly from the",
        "  signs of D, c', b' (Fractions); t = (-b' +- sqrt(D))/a with the sqrt in mpmath (80 digits)",
        "  and the final rounding to the nearest f32 (ties to even) verified exactly against the",
        "  neighbouring f32 midpoints.",
    ],
    "plane": [
        "Reference: t = ((p-o).n)/(d.n), exact rational (Fractions), rounded to the nearest f32;",
        "  hit iff t in (0, inf); d.n = 0, non-finite input, zero d or zero n -> miss.",
    ],
    "triangle": [
        "Reference: two-sided; solve o + t d = a + u (b-a) + v (c-a) exactly (Fractions, Cramer /",
        "  Moller-Trumbore quantities); hit iff t > 0, u >= 0, v >= 0, u + v <= 1; det = 0, zero area,",
        "  zero d or non-finite input -> miss.  t, u, v are exact rationals rounded to the nearest f32.",
        "  (u weights vertex b, v weights vertex c.)",
    ],
}

FILTER_TEXT = [
    "Filters (every case below): (a) decidable at 2 ulps: each decision quantity q satisfies",
    "  |q| > 1.5 * sum_i |dq/dx_i| * 2 ulp_f32(x_i) (exact gradients), and 16 random 2-ulp",
    "  perturbations of all inputs re-classify identically; (b) well conditioned: for every listed",
    "  t, sum_i |dt/dx_i| * 2 ulp_f32(x_i) <= 2e-6 |t|, and <= 2e-6 (absolute) for u and v.",
]


def header(kind, fname, title_lines, seed_note=None, filters=True, extra=None):
    seed = SEEDS.get(fname)
    h = ["# raylane test vectors: %s" % fname]
    h += [("# " + s) if s else "#" for s in title_lines]
    h.append("#")
    if seed is not None:
        h.append("# Generated by `%s` (random.Random(%d)); do not edit by hand." % (RERUN, seed))
    else:
        h.append("# Generated by `%s` (hand-picked cases, no randomness); do not edit by hand." % RERUN)
    if seed_note:
        h.append("# " + seed_note)
    h.append("# Format: " + GRAMMAR[kind])
    h.append("# Inputs are exact f32 values, written as the shortest decimal that round-trips to them;")
    h.append("#   expected outputs are the exact answer for those f32 inputs, rounded to the nearest f32.")
    h += ["# " + s for s in SEMANTICS[kind]]
    if filters:
        h += ["# " + s for s in FILTER_TEXT]
    if extra:
        h += ["# " + s for s in extra]
    h.append("")
    return h


def case_line(res):
    f = [fmt32(x) for x in res.xs]
    if res.kind == "sphere":
        s = "sphere   %s %s %s  %s %s %s  %s %s %s  %s" % tuple(f)
    elif res.kind == "plane":
        s = "plane    %s %s %s  %s %s %s  %s %s %s  %s %s %s" % tuple(f)
    else:
        s = "triangle %s %s %s  %s %s %s  %s %s %s  %s %s %s  %s %s %s" % tuple(f)
    out = "miss" if not res.out else " ".join(fmt32(x) for x in res.out)
    if res.record and res.out:
        out += "  ~ " + " ".join(fmt32(x) for x in cond_values(res))
    return s + "  -> " + out


def up32(x):
    """x (a nonnegative mpf) rounded up to 3 significant decimal digits, then to f32: a
    conditioning needs no more digits, and short numbers keep the files small."""
    q = mp2fr(mpf(x))
    if q == 0:
        return 0.0
    e = 0
    while q >= 1000 * F(10) ** e:
        e += 1
    while q < 100 * F(10) ** e:
        e -= 1
    m = -((-q) // (F(10) ** e))          # ceil(q / 10^e), 100 <= m <= 1000
    return dec_to_f32_exact("%de%d" % (m, e))


def cond_values(res):
    """The conditioning written after `~`, one number per expected value: for t, the relative
    change a 2-ulp move of the inputs can cause (first order, sum over the inputs of
    |dt/dx_i| 2 ulp(x_i), over |t|); for u and v the same sum, absolute.  Rounded up to 3
    significant digits."""
    if res.kind == "triangle":
        vals = [res.sens[0] / abs(res.exact[0]), res.sens[1], res.sens[2]]
    else:
        vals = [s / abs(t) for s, t in zip(res.sens, res.exact)]
    return [up32(v) for v in vals]


SUMMARY = []


def write_file(fname, lines, cases):
    path = os.path.join(OUT_DIR, fname)
    with open(path, "w") as fh:
        fh.write("\n".join(lines).rstrip("\n") + "\n")
    hits = sum(1 for c in cases if c.hit)
    SUMMARY.append((fname, len(cases), hits, len(cases) - hits))


def count_note(cases):
    hits = sum(1 for c in cases if c.hit)
    return "%d cases: %d hits, %d misses." % (len(cases), hits, len(cases) - hits)


def fmt_sci(x, p=2):
    return mp.nstr(x, p, min_fixed=-3, max_fixed=6)


# ---------------------------------------------------------------------------
# sphere_lecture.txt
# ---------------------------------------------------------------------------

def mp_unit32(v):
    """f32 rounding (single, exact rounding) of the real unit vector along v."""
    n = mp.sqrt(sum(mpf(x) ** 2 for x in v))
    return tuple(round32(mp2fr(mpf(x) / n)) for x in v)


def gen_sphere_lecture():
    fname = "sphere_lecture.txt"
    c = (5.0, 5.0, 5.0)
    r = 3.0
    s3, s6, s31 = mp.sqrt(3), mp.sqrt(6), mp.sqrt(31)
    lect = [
        ((0, 0, 0), (1, 1, 1), "t = 5 sqrt(3) -+ 3", (5 * s3 - 3, 5 * s3 + 3), "1 1 1 / sqrt(3)"),
        ((0, 0, 0), (1, 2, 2), "t = 25/3 -+ sqrt(31)/3", ((25 - s31) / 3, (25 + s31) / 3), "1 2 2 / 3"),
        ((0, 0, 0), (1, 3, 4), "miss: r^2 - b^2 = -58/13 (b = distance of c from the line)", (), "1 3 4 / sqrt(26)"),
        ((1, 0, 1), (1, 2, 1), "t = 2 sqrt(6) (point (3,4,3)) and 4 sqrt(6)", (2 * s6, 4 * s6), "1 2 1 / sqrt(6)"),
    ]
    unnorm = {
        (1, 1, 1): ("t = 5 -+ sqrt(3)", (5 - s3, 5 + s3)),
        (1, 2, 2): ("t = (25 -+ sqrt(31))/9", ((25 - s31) / 9, (25 + s31) / 9)),
        (1, 3, 4): ("miss", ()),
        (1, 2, 1): ("t = 2 and 4 (exactly)", (mpf(2), mpf(4))),
    }
    body = []
    cases = []
    checks = []
    body.append("# --- unit directions (f32-rounded) ---")
    for o, dint, text, closed, dname in lect:
        d = mp_unit32(dint)
        res = accept("sphere", list(o) + list(d) + list(c) + [r], cond="raw")
        assert res is not None, ("lecture case rejected", o, dint)
        body.append("# o = (%d,%d,%d), d = (%s): %s  [closed form: %s]" % (
            o + (dname, text, " ".join(mp.nstr(x, 12) for x in closed) or "miss")))
        body.append(case_line(res))
        cases.append(res)
        checks.append((o, dname, closed, res))
    body.append("")
    body.append("# --- the same rays with unnormalised integer directions (t scales by 1/|d|) ---")
    for o, dint, _text, _closed, _dn in lect:
        text, closed = unnorm[dint]
        res = accept("sphere", list(o) + list(dint) + list(c) + [r], cond="raw")
        assert res is not None
        body.append("# o = (%d,%d,%d), d = (%d,%d,%d): %s  [closed form: %s]" % (
            o + dint + (text, " ".join(mp.nstr(x, 12) for x in closed) or "miss")))
        body.append(case_line(res))
        cases.append(res)
        checks.append((o, "%d %d %d" % dint, closed, res))
    # the f32 answers must match the closed forms to ~1e-6
    for o, dn, cv, res in checks:
        assert len(cv) == len(res.out), (o, dn)
        for x, y in zip(cv, res.out):
            assert abs(x - y) <= mpf("1e-6") * abs(x), (o, dn, x, y)
    lines = header("sphere", fname, [
        "lecture worked examples: sphere centre (5,5,5), radius 3.",
        "Unit directions are the f32 roundings of the exact unit vectors, so the expected values are the",
        "exact answers for those f32 inputs; they agree with the closed forms (comment above each case)",
        "to ~1e-6 relative.  The second block repeats the rays with the unnormalised integer directions.",
        count_note(cases),
    ])
    write_file(fname, lines + body, cases)
    return checks


# ---------------------------------------------------------------------------
# sphere_random.txt
# ---------------------------------------------------------------------------

def gen_sphere_random():
    fname = "sphere_random.txt"
    rng = random.Random(SEEDS[fname])
    st = Stats()
    plan = [("two roots, origin outside", 105), ("origin inside (exit root only)", 45),
            ("sphere behind the origin (miss)", 45), ("line passes beside the sphere (miss)", 75),
            ("fully random ray", 30)]
    out_sections = []
    allcases = []
    idx = 0
    for cat, n in plan:
        got = []
        while len(got) < n:
            idx += 1
            unit = (idx % 2 == 0)
            o = rand_box(rng, 20)
            c = rand_box(rng, 20)
            r = rng.uniform(0.1, 8)
            if cat.startswith("origin inside"):
                o = vadd(c, vscale(r * rng.uniform(0, 0.95), rand_unit(rng)))
                dv = rand_unit(rng)
            else:
                if vnorm(vsub(o, c)) < 1.05 * r:
                    continue
                if cat.startswith("two") or cat.startswith("sphere behind"):
                    tgt = vadd(c, vscale(r * rng.uniform(0, 0.95), rand_unit(rng)))
                    dv = vsub(tgt, o)
                    if cat.startswith("sphere behind"):
                        dv = vscale(-1, dv)
                elif cat.startswith("line passes"):
                    e = rand_perp(rng, vunit(vsub(c, o)))
                    tgt = vadd(c, vscale(r * rng.uniform(1.05, 3.0), e))
                    dv = vsub(tgt, o)
                else:
                    dv = rand_unit(rng)
            d = dir32(rng, dv, unit)
            res = accept("sphere", list(o) + list(d) + list(c) + [r], st)
            if res is not None:
                res.unit = unit
                res.record = True
                got.append(res)
        out_sections.append((cat, got))
        allcases += got
    n_inside = sum(1 for c in allcases if c.q[2] < 0)
    n_behind = sum(1 for c in allcases if c.q[2] > 0 and c.q[3] > 0 and c.q[1] > 0)
    lines = header("sphere", fname, [
        "random rays and spheres: origins and centres uniform in [-20,20]^3, radius uniform in",
        "[0.1, 8]; directions alternate between unit (normalised, then f32-rounded) and non-unit",
        "(length log-uniform in [0.01, 100]).",
        count_note(allcases) + " %d with the origin inside, %d with the sphere behind." % (n_inside, n_behind),
    ])
    for cat, got in out_sections:
        lines.append("# --- %s: %d cases ---" % (cat, len(got)))
        lines += [case_line(r) for r in got]
        lines.append("")
    write_file(fname, lines, allcases)
    return st


# ---------------------------------------------------------------------------
# sphere_far.txt
# ---------------------------------------------------------------------------

def gen_sphere_far():
    fname = "sphere_far.txt"
    rng = random.Random(SEEDS[fname])
    per_k = {}
    blocks = []
    allcases = []
    global MC_RNG
    main_rng, main_mc = rng, MC_RNG
    # k = 4, 5 were added later: their own streams, so that k >= 6 and every later file keep
    # the cases they had
    low_rng = random.Random(SEEDS["sphere_far_low_k"])
    low_mc = random.Random(SEEDS["sphere_far_low_k"] + 1000)
    for k in range(4, 21):
        if k < 6:
            rng, MC_RNG = low_rng, low_mc
        else:
            rng, MC_RNG = main_rng, main_mc
        kst = {"uniform": Stats(), "rim": Stats()}
        got = {"uniform": [], "rim-in": [], "rim-out": []}
        quota = {"uniform": 20, "rim-in": 10, "rim-out": 10}
        rim_ranges = {}
        for bucket in ("uniform", "rim-in", "rim-out"):
            stt = kst["uniform" if bucket == "uniform" else "rim"]
            lo, hi = 0.002, 0.05     # initial |1 - l/r| range for the rim buckets
            rounds = 0
            while len(got[bucket]) < quota[bucket]:
                for _ in range(150):
                    if len(got[bucket]) >= quota[bucket]:
                        break
                    o = (0.0, 0.0, 0.0) if rng.random() < 0.25 else rand_box(rng, 10)
                    o = v32(o)
                    d = v32(rand_unit(rng))
                    r = f32(loguniform(rng, 0.01, 10.0))
                    L = r * 2.0 ** k * float(mp.power(2, rng.uniform(-0.25, 0.25)))
                    if bucket == "uniform":
                        x = rng.uniform(0, 2)
                    else:
                        delta = rng.uniform(lo, hi)
                        x = 1 - delta if bucket == "rim-in" else 1 + delta
                    dd = vunit(d)
                    e = rand_perp(rng, dd)
                    cc = vadd(vadd(o, vscale(L, dd)), vscale(x * r, e))
                    res = accept("sphere", list(o) + list(d) + list(cc) + [r], stt)
                    if res is None:
                        continue
                    res.record = True
                    if bucket != "uniform":
                        # classify by the actual (post-rounding) offset
                        want_hit = bucket == "rim-in"
                        if res.hit != want_hit:
                            stt.reject("rim case landed on the other side after f32 rounding")
                            stt.kept -= 1
                            continue
                    # actual l/r from the exact quantities: (l/r)^2 = 1 - D/(a r^2)
                    a, b, c, D = res.q
                    res.lr = math.sqrt(max(0.0, float(1 - D / (a * F(r) ** 2))))
                    res.dist = float(mp.sqrt(fr2mp(c + F(r) ** 2)) / fr2mp(F(r)))
                    got[bucket].append(res)
                if len(got[bucket]) < quota[bucket]:
                    rounds += 1
                    if rounds >= 1 and bucket != "uniform":
                        lo, hi = min(lo * 2, 0.4), min(hi * 2, 0.9)
                    if rounds > 12:
                        break
            rim_ranges[bucket] = (lo, hi)
        cases = got["uniform"] + got["rim-in"] + got["rim-out"]
        per_k[k] = (kst, rim_ranges, cases)
        allcases += cases
        blk = ["# === k = %d: |c - o| / r ~ 2^%d; %s ===" % (k, k, count_note(cases))]
        blk.append("#   l/r uniform in [0,2]: %s" % kst["uniform"])
        blk.append("#   near rim: %s; |1 - l/r| finally drawn from [%.3g, %.3g]" % (
            kst["rim"], rim_ranges["rim-in"][0], rim_ranges["rim-in"][1]))
        for tag in ("uniform", "rim-in", "rim-out"):
            for res in got[tag]:
                blk.append("# k=%d %s l/r=%.6f |c-o|/r=%.4g" % (k, tag, res.lr, res.dist))
                blk.append(case_line(res))
        blk.append("")
        blocks.append(blk)
    lines = header("sphere", fname, [
        "far small spheres, unit directions: |c - o| / r ~ 2^k for k = 4..20 (k = 4, 5 from their own",
        "random streams, seeds %d and %d for the Monte-Carlo check)." % (SEEDS["sphere_far_low_k"], SEEDS["sphere_far_low_k"] + 1000),
        "THIS FILE IS WHAT THE FOCAL METHOD MUST GET RIGHT UP TO |c - o|/r = 2^20.",
        "Origin uniform in [-10,10]^3 (25% exactly at 0), direction uniform unit (f32-rounded), r",
        "log-uniform in [0.01, 10], centre at distance 2^k r * 2^U(-1/4,1/4) along the ray plus a",
        "perpendicular offset l: l/r uniform in [0,2] (20 per k) or near the rim, 10 inside (hit) and",
        "10 outside (miss), |1 - l/r| in [0.002, 0.05] -- widened by 2x per round of 150 attempts",
        "whenever the filters left the quota unfilled (the 2-ulp band of D grows like 2^k; see the",
        "per-k comment).  l/r printed per case is the actual value after f32 rounding.",
        count_note(allcases),
    ])
    for blk in blocks:
        lines += blk
    write_file(fname, lines, allcases)
    return per_k


# ---------------------------------------------------------------------------
# sphere_ground.txt
# ---------------------------------------------------------------------------

def ground_case(rng, R, h, off, elev_deg):
    """Origin at height ~h above the sphere centre (0,-R,0), radius R, with
    horizontal offset off=(x,z); unit direction elev_deg below (>0) or above
    (<0) the local horizon, random azimuth.  o is snapped so that o - c is
    exactly representable in f32."""
    x, z = off
    x, z = f32(x), f32(z)
    Rm = mpf(R)
    y = mp.sqrt((Rm + h) ** 2 - x * x - z * z) - Rm
    u = ulp32(float(Rm + y))        # snap y + R to the f32 grid around R + h
    yy = mp2fr(mp.nint((y + Rm) / fr2mp(u))) * u - F(R)
    yv = round32(yy)
    assert F(yv) == yy
    o = (x, yv, z)
    # local frame at o
    up = vunit((x, float(yy + F(R)), z))
    e1 = rand_perp(rng, up)
    e2 = vcross(up, e1)
    az = rng.uniform(0, 2 * math.pi)
    ca, sa = float(mp.cos(az)), float(mp.sin(az))
    hor = vunit(vadd(vscale(ca, e1), vscale(sa, e2)))
    th = mp.radians(elev_deg)
    ct, stt = float(mp.cos(th)), float(mp.sin(th))
    d = v32(vunit(vsub(vscale(ct, hor), vscale(stt, up))))
    return list(o) + list(d) + [0.0, -float(R), 0.0, float(R)]


def gen_sphere_ground():
    fname = "sphere_ground.txt"
    rng = random.Random(SEEDS[fname])
    st = Stats()
    blocks = []
    allcases = []
    maxrel = {}
    maxfar = [mpf(0)]
    for R in (1000.0, 4000.0, 10000.0, 1e5, 1e6):
        got = []
        nh, nm = 10, 2
        while len([c for c in got if c.hit]) < nh:
            h = rng.uniform(0.5, 5)
            off = (0.0, 0.0) if rng.random() < 0.5 else (rng.uniform(-3, 3), rng.uniform(-3, 3))
            dip = float(mp.degrees(mp.acos(mpf(R) / (mpf(R) + h))))
            lo = max(5.0, dip + 2.0)
            el = rng.uniform(lo, 60.0)
            res = accept("sphere", ground_case(rng, R, h, off, el), st, cond="report")
            if res is None or not res.hit:
                continue
            res.h, res.el, res.offs = h, el, off
            got.append(res)
        while len(got) < nh + nm:
            h = rng.uniform(0.5, 5)
            el = -rng.uniform(5.0, 60.0)
            res = accept("sphere", ground_case(rng, R, h, (0.0, 0.0), el), st, cond="report")
            if res is None or res.hit:
                continue
            res.h, res.el, res.offs = h, el, (0.0, 0.0)
            got.append(res)
        blk = ["# === R = %s ===" % fmt32(R)]
        for res in got:
            if res.hit:
                maxrel[R] = max(maxrel.get(R, 0), res.relsens[0])
                maxfar[0] = max(maxfar[0], res.relsens[1])
                blk.append("# R=%s h~%.3f offset=(%.3g,%.3g) %.2f deg below horizon; 2-ulp rel. sensitivity t0 %s, t1 %s" % (
                    fmt32(R), res.h, res.offs[0], res.offs[1], res.el, fmt_sci(res.relsens[0]), fmt_sci(res.relsens[1])))
            else:
                blk.append("# R=%s h~%.3f pointing %.2f deg above the horizon: miss" % (fmt32(R), res.h, -res.el))
            blk.append(case_line(res))
        blk.append("")
        blocks.append(blk)
        allcases += got
    lines = header("sphere", fname, [
        "huge 'ground' sphere (precision lecture scene): centre (0,-R,0), radius R, R in {1000, 4000,",
        "1e4, 1e5, 1e6}; origin at height h in [0.5,5] above the surface (half of them with x,z offsets",
        "in [-3,3]), snapped so that o - c is exactly representable in f32; unit directions 5-60 deg",
        "below the local horizon (and above the horizon's dip), so the near root ~ h/sin(angle) is tiny",
        "next to the far root ~ 2 R sin(angle) (catastrophic cancellation in (-b' - sqrt(D))/a); plus",
        "2 rays per R pointing up (miss).",
        count_note(allcases),
        "",
        "NOTE: filter (a) (decidability) applies, but filter (b) CANNOT hold in this scene: moving R or",
        "c_y by 2 ulps moves the surface by ~4 ulp(R), so the near root's relative 2-ulp sensitivity is",
        "~4 ulp(R)/h (up to ~5e-4 for R = 1000 and ~0.5 for R = 1e6 at h = 0.5).  It is printed per",
        "case (first-order sum over all inputs); use it to size the tolerance on t0.  Largest per R:",
        "  " + ", ".join("R=%s: %s" % (fmt32(R), fmt_sci(v)) for R, v in sorted(maxrel.items())) + ".",
        "The far root is much better conditioned (largest relative sensitivity %s, at the" % fmt_sci(maxfar[0]),
        "shallowest angles: ~2 ulp(R) / (R sin^2(angle))).",
    ], filters=False, extra=[
        "Filters: (a) as in the other files (|q| > 1.5 * 2-ulp band for D, c', b'; Monte-Carlo",
        "  re-classification); (b) not applied -- sensitivities are reported instead (see NOTE).",
    ])
    for blk in blocks:
        lines += blk
    write_file(fname, lines, allcases)
    return st, maxrel


# ---------------------------------------------------------------------------
# sphere_special.txt
# ---------------------------------------------------------------------------

def gen_sphere_special():
    fname = "sphere_special.txt"
    rng = random.Random(SEEDS[fname])
    u111 = list(mp_unit32((1, 1, 1)))
    u122 = list(mp_unit32((1, 2, 2)))
    u_m = list(mp_unit32((-3, 1, 2)))
    groups = []

    def toward(o, tgt, scale=1.0):
        d = vunit(vsub(tgt, o))
        return list(v32(vscale(scale, d)))

    g = ("origin inside the sphere: only the exit root", [
        ("origin at the centre, +z", [1, 2, 3, 0, 0, 1, 1, 2, 3, 2], "raw"),
        ("origin at the centre, diagonal", [1, 2, 3] + u111 + [1, 2, 3, 2], "raw"),
        ("origin at the centre, non-unit diagonal", [1, 2, 3, 3, 3, 3, 1, 2, 3, 2], "raw"),
        ("origin off-centre, +y", [0.5, -0.25, 0.125, 0, 1, 0, 0, 0, 0, 1], "raw"),
        ("origin off-centre, -y", [0.5, -0.25, 0.125, 0, -1, 0, 0, 0, 0, 1], "raw"),
        ("origin just inside the surface, pointing inwards", [0, 0, 0.999, 0, 0, -1, 0, 0, 0, 1], "raw"),
        ("origin inside, oblique", [0.5, 1.5, 1.25] + u_m + [1, 1, 1, 3], "raw"),
        ("origin inside a big sphere", [10, -20, 30] + u122 + [0, 0, 0, 100], "raw"),
    ])
    groups.append(g)
    g = ("sphere behind the origin: miss", [
        ("on the axis, pointing away", [0, 0, 10, 0, 0, 1, 0, 0, 0, 2], "raw"),
        ("lecture sphere, reversed ray", [0, 0, 0] + [-x for x in u111] + [5, 5, 5, 3], "raw"),
        ("oblique, pointing away", [3, -4, 12] + toward((0, 0, 0), (2, -3, 5)) + [-1, 2, -3, 1.5], "raw"),
        ("non-unit, pointing away", [-7, 0, 0, -1e-3, 0, 0, 0, 0, 0, 5], "raw"),
    ])
    groups.append(g)
    g = ("non-unit directions: tiny (|d| ~ 1e-3) and huge (|d| ~ 1e3)", [
        ("|d| = 1e-3 along +z", [0, 0, 0, 0, 0, 1e-3, 0, 0, 10, 2], "raw"),
        ("|d| = 1e3 along +z", [0, 0, 0, 0, 0, 1e3, 0, 0, 10, 2], "raw"),
        ("lecture ray (1,2,2) * 1e-3", [0, 0, 0, 1e-3, 2e-3, 2e-3, 5, 5, 5, 3], "raw"),
        ("lecture ray (1,2,2) * 1e3", [0, 0, 0, 1e3, 2e3, 2e3, 5, 5, 5, 3], "raw"),
        ("lecture ray (1,1,1)/sqrt3 * 1e-3", [0, 0, 0] + [x * 1e-3 for x in u111] + [5, 5, 5, 3], "raw"),
        ("lecture ray (1,1,1)/sqrt3 * 1e3", [0, 0, 0] + [x * 1e3 for x in u111] + [5, 5, 5, 3], "raw"),
        ("origin inside, |d| = 1e-3", [0.5, 0, 0, 0, 1e-3, 0, 0, 0, 0, 1], "raw"),
        ("origin inside, |d| = 1e3", [0.5, 0, 0, 0, 1e3, 0, 0, 0, 0, 1], "raw"),
        ("oblique |d| ~ 1e-3", [1, -2, 0.5] + toward((1, -2, 0.5), (6, 3, -4), 1e-3) + [6.5, 2.5, -4, 1.75], "raw"),
        ("oblique |d| ~ 1e3", [1, -2, 0.5] + toward((1, -2, 0.5), (6, 3, -4), 1e3) + [6.5, 2.5, -4, 1.75], "raw"),
        ("miss beside, |d| ~ 1e3", [0, 0, 0, 1e3, 0, 0, 10, 3, 0, 2], "raw"),
    ])
    groups.append(g)
    g = ("axis-aligned rays through the centre", [
        ("+x", [-10, 0, 0, 1, 0, 0, 0, 0, 0, 1], "raw"),
        ("-y", [0, 7, 0, 0, -1, 0, 0, 0, 0, 2.5], "raw"),
        ("+z, |d| = 2", [3, 4, -20, 0, 0, 2, 3, 4, 5, 1.5], "raw"),
        ("-x", [0, 0, 0, -1, 0, 0, -6, 0, 0, 0.5], "raw"),
        ("+y from inside", [2, -1, 2, 0, 1, 0, 2, 0, 2, 3], "raw"),
        ("-z, sphere behind", [0, 0, 0, 0, 0, -1, 0, 0, 4, 1], "raw"),
    ])
    groups.append(g)
    big = (10000.0, 10000.0, 10000.0)
    c2 = (12345.5, -9876.25, 10240.0)
    g = ("large coordinates: centre ~1e4, radius ~1", [
        ("origin at 0, diagonal", [0, 0, 0] + u111 + list(big) + [1], "raw"),
        ("origin near 0, aimed 0.5 (0.4 r) off-centre", [1, 2, 3] + toward((1, 2, 3), vadd(c2, (0.3, 0.4, 0.0))) + list(c2) + [1.25], "raw"),
        ("origin near 0, aimed 1.3 r off-centre (miss)", [1, 2, 3] + toward((1, 2, 3), vadd(c2, (0.0, 0.0, 1.625))) + list(c2) + [1.25], "raw"),
        ("on the x axis, offset 0.5", [0, 0.5, 0, 1, 0, 0, 10000, 0, 0, 1], "raw"),
        ("origin near the centre (o - c exact; (b) on translated inputs)", [9995, 10000.5, 10000.25, 1, 0, 0] + list(big) + [1], "translated"),
        ("origin near the centre, oblique through the centre (o - c exact; (b) translated)", [9999, 9998, 9998] + u122 + list(big) + [1], "translated"),
        ("origin inside, centre ~1e4 ((b) translated)", [10000.25, 9999.875, 10000, 0, 0, 1] + list(big) + [1], "translated"),
    ])
    groups.append(g)
    g = ("tiny spheres (r = 1e-3) near the origin", [
        ("on the z axis", [0, 0, 0, 0, 0, 1, 0, 0, 0.004, 1e-3], "raw"),
        ("oblique, aimed at the centre", [0, 0, 0] + toward((0, 0, 0), (0.01, 0.02, -0.005)) + [0.01, 0.02, -0.005, 1e-3], "raw"),
        ("oblique, aimed ~0.6 r off-centre", [0, 0, 0] + toward((0, 0, 0), (0.01, 0.02, -0.0044)) + [0.01, 0.02, -0.005, 1e-3], "raw"),
        ("oblique, aimed ~1.5 r off-centre (miss)", [0, 0, 0] + toward((0, 0, 0), (0.01, 0.02, -0.0035)) + [0.01, 0.02, -0.005, 1e-3], "raw"),
        ("origin inside a tiny sphere", [3e-4, 0, 0, 0, 1, 0, 0, 0, 0, 1e-3], "raw"),
        ("tiny sphere at distance 1", [0, 0, 0] + u111 + list(v32(vscale(1.0, vunit((1, 1, 1))))) + [1e-3], "raw"),
        ("tiny sphere behind", [0, 0, 0, 0, 0, -1, 0, 0, 0.004, 1e-3], "raw"),
    ])
    groups.append(g)

    lines_body = []
    allcases = []
    dropped = []
    for title, items in groups:
        lines_body.append("# --- %s ---" % title)
        for name, xs, cond in items:
            st = Stats()
            res = accept("sphere", [float(x) for x in xs], st, cond=cond)
            if res is None:
                dropped.append((title, name, str(st)))
                continue
            lines_body.append("# %s" % name)
            lines_body.append(case_line(res))
            allcases.append(res)
        lines_body.append("")
    lines = header("sphere", fname, [
        "hand-picked structure cases: origin inside, sphere behind, tiny (1e-3) and huge (1e3)",
        "non-unit directions, axis-aligned rays through the centre, large coordinates (centre ~1e4,",
        "r ~1), tiny spheres (r = 1e-3) near the origin.",
        "Cases marked '(b) translated' have o - c exactly representable in f32; filter (b) is",
        "evaluated on the translated inputs (o - c, d, 0, r) since the absolute 2-ulp perturbation of",
        "coordinates ~1e4 would swamp t ~ 1 otherwise; filter (a) uses the raw inputs.",
        count_note(allcases),
    ])
    write_file(fname, lines + lines_body, allcases)
    return dropped


# ---------------------------------------------------------------------------
# sphere_bad.txt
# ---------------------------------------------------------------------------

SPH_FIELDS = ["ox", "oy", "oz", "dx", "dy", "dz", "cx", "cy", "cz", "r"]


def bad_file(kind, fname, title, base_hit, fields, groups_inf, extra_cases):
    body = []
    cases = []
    base = [f32(x) for x in base_hit]
    ref = EVAL[kind](base)
    assert ref.hit and ref.flag is None
    body.append("# base case (a valid hit, NOT part of this file): %s" % case_line(ref))
    body.append("")

    def add(comment, xs):
        xs = [f32(x) for x in xs]
        res = EVAL[kind](xs)
        assert not res.hit, (comment, xs)
        assert res.flag is not None, (comment, xs)
        body.append("# " + comment + "  [" + res.flag + "]")
        body.append(case_line(res))
        cases.append(res)

    body.append("# --- NaN in each input field of the base case ---")
    for i, nm in enumerate(fields):
        xs = list(base)
        xs[i] = NAN
        add("NaN in %s" % nm, xs)
    body.append("")
    body.append("# --- +inf / -inf in each input field of the base case ---")
    for i in groups_inf:
        for v in (INF, -INF):
            xs = list(base)
            xs[i] = v
            add("%s in %s" % (fmt32(v), fields[i]), xs)
    body.append("")
    for sect, items in extra_cases:
        body.append("# --- %s ---" % sect)
        for comment, xs in items:
            add(comment, xs)
        body.append("")
    lines = header(kind, fname, title + ["Every expectation is `miss`; no filters apply.", count_note(cases)],
                   filters=False)
    write_file(fname, lines + body, cases)


def gen_sphere_bad():
    base = [0, 0, 0] + list(mp_unit32((1, 1, 1))) + [5, 5, 5, 3]
    u = list(mp_unit32((1, 1, 1)))
    extra = [
        ("all-NaN / all-inf", [
            ("every field NaN", [NAN] * 10),
            ("origin all +inf", [INF, INF, INF] + u + [5, 5, 5, 3]),
            ("direction (inf, inf, inf) -- normalising would give NaN", [0, 0, 0, INF, INF, INF, 5, 5, 5, 3]),
            ("direction (inf, 0, 0) towards a sphere on the x axis", [0, 0, 0, INF, 0, 0, 10, 0, 0, 1]),
            ("radius +inf with the origin outside", [0, 0, 0] + u + [5, 5, 5, INF]),
            ("centre at inf, radius inf", [0, 0, 0] + u + [INF, 5, 5, INF]),
        ]),
        ("zero direction", [
            ("d = (0, 0, 0), origin outside", [0, 0, 0, 0, 0, 0, 5, 5, 5, 3]),
            ("d = (0, 0, 0), origin inside", [5, 5, 4, 0, 0, 0, 5, 5, 5, 3]),
            ("d = (-0, 0, -0), origin inside", [5, 5, 4, -0.0, 0, -0.0, 5, 5, 5, 3]),
        ]),
        ("zero / negative / NaN radius", [
            ("r = 0, ray through the centre", [0, 0, 0] + u + [5, 5, 5, 0]),
            ("r = -0, ray through the centre", [0, 0, 0] + u + [5, 5, 5, -0.0]),
            ("r = 0, origin at the centre", [5, 5, 5] + u + [5, 5, 5, 0]),
            ("r = -3, origin outside, ray through the centre (|r| would hit)", [0, 0, 0] + u + [5, 5, 5, -3]),
            ("r = -3, origin inside |r| (|r| would give an exit root)", [5, 5, 4] + u + [5, 5, 5, -3]),
            ("r = -3, origin at the centre", [5, 5, 5, 0, 0, 1, 5, 5, 5, -3]),
            ("r = -1e-3, origin inside |r|", [0, 0, 0, 1, 0, 0, 0, 0, 0, -1e-3]),
            ("r = -inf", [0, 0, 0] + u + [5, 5, 5, -INF]),
            ("r = NaN, origin inside", [5, 5, 4] + u + [5, 5, 5, NAN]),
        ]),
    ]
    bad_file("sphere", "sphere_bad.txt",
             ["bad sphere inputs: NaN in every field, +-inf in origin/direction/centre/radius,",
              "zero direction, zero/negative/NaN radius."],
             base, SPH_FIELDS, list(range(10)), extra)


# ---------------------------------------------------------------------------
# plane_random.txt
# ---------------------------------------------------------------------------

def gen_plane_random():
    fname = "plane_random.txt"
    rng = random.Random(SEEDS[fname])
    st = Stats()
    secs = []
    allcases = []
    plan = [("hit in front", 100), ("plane behind the origin (miss)", 60), ("fully random", 40)]
    idx = 0
    for cat, n in plan:
        got = []
        while len(got) < n:
            idx += 1
            o = rand_box(rng, 20)
            p = rand_box(rng, 20)
            nrm = dir32(rng, rand_unit(rng), idx % 2 == 0)
            d = dir32(rng, rand_unit(rng), (idx // 2) % 2 == 0)
            if cat != "fully random":
                num = vdot(vsub(p, o), nrm)
                den = vdot(d, nrm)
                want = 1 if cat == "hit in front" else -1
                if num * den * want < 0:
                    d = tuple(-x for x in d)
            res = accept("plane", list(o) + list(d) + list(p) + list(nrm), st)
            if res is not None:
                res.record = True
                got.append(res)
        secs.append((cat, got))
        allcases += got
    # nearly parallel rays with axis-aligned normals (zero components keep them
    # decidable and well conditioned)
    got = []
    stp = Stats()
    axes = [(0, 0, 1), (0, 1, 0), (1, 0, 0), (0, 0, -2.5), (0, 3, 0), (-1, 0, 0)]
    while len(got) < 12:
        ax = axes[len(got) % len(axes)]
        k = [i for i in range(3) if ax[i] != 0][0]
        o = rand_box(rng, 20)
        p = rand_box(rng, 20)
        eps = loguniform(rng, 1e-4, 1e-2)
        dv = list(rand_unit(rng))
        dv[k] = 0.0
        dv = list(vunit(dv))
        num_sign = (p[k] - o[k]) * ax[k]
        want = 1 if len(got) % 3 != 2 else -1     # 2/3 hits
        dv[k] = eps * (1 if num_sign * ax[k] * want > 0 else -1)
        d = v32(dv)
        res = accept("plane", list(o) + list(d) + list(p) + [float(x) for x in ax], stp)
        if res is not None:
            res.record = True
            got.append(res)
    secs.append(("nearly parallel rays (|d.n| / (|d||n|) in [1e-4, 1e-2]), axis-aligned normals", got))
    allcases += got
    lines = header("plane", fname, [
        "random planes: origins and plane points uniform in [-20,20]^3; normals and directions",
        "alternate unit (normalised then f32-rounded) / non-unit (length log-uniform [0.01, 100]);",
        "hits in front, planes behind (miss), fully random; plus nearly parallel but decidable rays",
        "(axis-aligned normals: the exact zeros keep d.n well determined).",
        count_note(allcases),
    ])
    for cat, got in secs:
        lines.append("# --- %s: %d cases ---" % (cat, len(got)))
        lines += [case_line(r) for r in got]
        lines.append("")
    write_file(fname, lines, allcases)
    return st, stp


# ---------------------------------------------------------------------------
# plane_bad.txt
# ---------------------------------------------------------------------------

PL_FIELDS = ["ox", "oy", "oz", "dx", "dy", "dz", "px", "py", "pz", "nx", "ny", "nz"]


def gen_plane_bad():
    base = [1, 2, 3] + list(mp_unit32((1, -2, 2))) + [0, -5, 0, 0, 1, 0]
    s = f32(0.1)
    t = f32(0.7)
    extra = [
        ("parallel rays: d.n = 0 exactly", [
            ("axis-aligned: d along x, n along y", [0, 1, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0]),
            ("axis-aligned: d along -z, n along x, non-unit", [3, -2, 7, 0, 0, -5, -1, 0, 0, 2, 0, 0]),
            ("d = (1,1,0), n = (1,-1,0)", [0, 0, 0, 1, 1, 0, 5, 0, 0, 1, -1, 0]),
            ("d = (3,4,0), n = (4,-3,5)", [1, 1, 1, 3, 4, 0, 0, 0, 9, 4, -3, 5]),
            ("d = (0.1,0.7,0)f32, n = (0.7,-0.1,0)f32: d.n = 0 exactly", [-3, 2, 1, s, t, 0, 4, 4, 4, t, -s, 0]),
            ("d = (1,2,3), n = (1,1,-1)", [0, 0, 0, 1, 2, 3, 0, 0, -4, 1, 1, -1]),
        ]),
        ("ray lying in the plane (d.n = 0 and (p-o).n = 0)", [
            ("in the plane y = 0", [0, 0, 0, 1, 0, 0, 5, 0, 5, 0, 1, 0]),
            ("in the plane x + y - z = 0", [1, 1, 2, 1, 2, 3, 0, 0, 0, 1, 1, -1]),
        ]),
        ("origin on the plane, d.n != 0: t = 0 exactly, not in the open interval", [
            ("y = 2 plane through the origin, ray leaving it", [1, 2, 7, 0, 1, 0, 3, 2, 5, 0, 1, 0]),
            ("oblique, origin = p", [1.5, -2.25, 3, 0.5, 0.25, 1, 1.5, -2.25, 3, 1, 2, 2]),
        ]),
        ("zero normal", [
            ("n = (0,0,0)", [1, 2, 3] + list(mp_unit32((1, -2, 2))) + [0, -5, 0, 0, 0, 0]),
            ("n = (-0,0,-0)", [1, 2, 3, 0, -1, 0, 0, -5, 0, -0.0, 0, -0.0]),
        ]),
        ("zero direction", [
            ("d = (0,0,0)", [1, 2, 3, 0, 0, 0, 0, -5, 0, 0, 1, 0]),
            ("d = (0,-0,0), origin on the plane", [1, -5, 3, 0, -0.0, 0, 0, -5, 0, 0, 1, 0]),
        ]),
        ("all non-finite", [
            ("every field NaN", [NAN] * 12),
            ("normal (inf, inf, inf)", [1, 2, 3, 0, -1, 0, 0, -5, 0, INF, INF, INF]),
            ("direction (0, -inf, 0) towards the plane", [1, 2, 3, 0, -INF, 0, 0, -5, 0, 0, 1, 0]),
        ]),
    ]
    bad_file("plane", "plane_bad.txt",
             ["bad / degenerate plane inputs: parallel rays (d.n = 0 exactly), ray in the plane, origin on",
              "the plane (t = 0 is outside the open interval), zero normal, zero direction, NaN/inf in every field."],
             base, PL_FIELDS, list(range(12)), extra)


# ---------------------------------------------------------------------------
# triangle_random.txt
# ---------------------------------------------------------------------------

def tri_point(a, b, c, u, v):
    return tuple(a[i] + u * (b[i] - a[i]) + v * (c[i] - a[i]) for i in range(3))


def gen_triangle_random():
    fname = "triangle_random.txt"
    rng = random.Random(SEEDS[fname])
    st = Stats()
    plan = [("hit (u, v uniform over the triangle)", 150), ("just outside an edge (miss)", 75),
            ("triangle behind the origin (miss)", 30), ("fully random ray", 45)]
    secs = []
    allcases = []
    idx = 0
    for cat, n in plan:
        got = []
        while len(got) < n:
            idx += 1
            a, b, c = (v32(rand_box(rng, 10)) for _ in range(3))
            o = rand_box(rng, 20)
            unit = idx % 2 == 0
            if cat.startswith("hit") or cat.startswith("triangle behind"):
                u, v = rng.random(), rng.random()
                if u + v > 1:
                    u, v = 1 - u, 1 - v
                P = tri_point(a, b, c, u, v)
                dv = vsub(P, o)
                if cat.startswith("triangle behind"):
                    dv = vscale(-1, dv)
            elif cat.startswith("just outside"):
                delta = loguniform(rng, 1e-4, 0.05)
                s = rng.random()
                edge = idx % 3
                if edge == 0:
                    u, v = -delta, s
                elif edge == 1:
                    u, v = s, -delta
                else:
                    u, v = s * (1 + delta), (1 - s) * (1 + delta)
                P = tri_point(a, b, c, u, v)
                dv = vsub(P, o)
            else:
                dv = rand_unit(rng)
            if vnorm(dv) < 1e-3:
                continue
            d = dir32(rng, dv, unit)
            res = accept("triangle", list(o) + list(d) + list(a) + list(b) + list(c), st)
            if res is not None:
                res.record = True
                got.append(res)
        secs.append((cat, got))
        allcases += got
    hits = [c for c in allcases if c.hit]
    nfront = sum(1 for c in hits if c.front)
    lines = header("triangle", fname, [
        "random triangles: vertices uniform in [-10,10]^3, origins uniform in [-20,20]^3; directions",
        "alternate unit (normalised, f32-rounded) / non-unit (length log-uniform in [0.01, 100]).",
        "Hits aim at a uniformly random point of the triangle; near misses aim at a point a distance",
        "delta (log-uniform in [1e-4, 0.05], in barycentric units) outside an edge.",
        count_note(allcases) + "  Hits: %d front-face (d.n < 0), %d back-face." % (nfront, len(hits) - nfront),
    ])
    for cat, got in secs:
        lines.append("# --- %s: %d cases ---" % (cat, len(got)))
        lines += [case_line(r) for r in got]
        lines.append("")
    write_file(fname, lines, allcases)
    return st


# ---------------------------------------------------------------------------
# triangle_special.txt
# ---------------------------------------------------------------------------

def gen_triangle_special():
    fname = "triangle_special.txt"
    rng = random.Random(SEEDS[fname])
    groups = []
    dropped = []

    def aim(o, tri, u, v, scale=1.0):
        P = tri_point(*tri, u, v)
        return list(v32(vscale(scale, vunit(vsub(P, o)))))

    # --- offset 1e4: random candidates until the quota of each kind is met ---
    off_items = []
    OFF = 10000.0
    quota = {"hit": 6, "miss outside edge ab-ac (u < 0)": 3, "miss beyond edge bc (u + v > 1)": 3}
    have = dict.fromkeys(quota, 0)
    off_st = Stats()
    i = 0
    while any(have[k] < quota[k] for k in quota):
        i += 1
        assert i < 5000
        tri = tuple(v32(vadd((OFF, OFF, OFF), vscale(rng.uniform(2, 8), rand_box(rng, 1)))) for _ in range(3))
        o = v32(vadd((OFF, OFF, OFF), rand_box(rng, 10)))
        kind = [k for k in quota if have[k] < quota[k]][0]
        if kind == "hit":
            u, v = rng.uniform(0.1, 0.6), rng.uniform(0.1, 0.3)
        elif kind.startswith("miss outside"):
            u, v = -rng.uniform(0.02, 0.2), rng.uniform(0.2, 0.8)
        else:
            u, v = rng.uniform(0.55, 0.9), rng.uniform(0.55, 0.9)
        d = aim(o, tri, u, v, 1.0 if i % 2 == 0 else rng.uniform(0.1, 10))
        xs = list(o) + d + list(tri[0]) + list(tri[1]) + list(tri[2])
        res = accept("triangle", xs, off_st, cond="translated")
        if res is None or res.hit != (kind == "hit"):
            continue
        have[kind] += 1
        off_items.append((kind + " (vertices/origin near (1e4,1e4,1e4); (b) translated)", xs, "translated"))
    groups.append(("coordinates offset by 1e4 (triangle and origin near (1e4,1e4,1e4)); candidates: " + str(off_st), off_items))

    T = ((0.0, 0.0, 0.0), (4.0, 0.0, 0.0), (0.0, 3.0, 0.0))     # normal (b-a)x(c-a) = +z
    items = [
        ("front face: from +z going down (d.n < 0)", [1, 1, 5, 0, 0, -1] + [x for p in T for x in p], "raw"),
        ("back face: from -z going up (d.n > 0)", [1, 1, -5, 0, 0, 1] + [x for p in T for x in p], "raw"),
        ("back face, oblique", [-1, -2, -6] + aim((-1, -2, -6), T, 0.3, 0.25) + [x for p in T for x in p], "raw"),
        ("back face, non-unit", [2, 2.5, -0.5] + aim((2, 2.5, -0.5), T, 0.1, 0.6, 7.5) + [x for p in T for x in p], "raw"),
        ("back face of a random triangle", None, "raw"),
    ]
    tr = tuple(v32(rand_box(rng, 10)) for _ in range(3))
    n = vcross(vsub(tr[1], tr[0]), vsub(tr[2], tr[0]))
    P = tri_point(*tr, 0.25, 0.35)
    o = v32(vsub(P, vscale(6.0, vunit(n))))     # behind the face: d.n > 0
    items[-1] = ("back face of a random triangle", list(o) + aim(o, tr, 0.25, 0.35) + [x for p in tr for x in p], "raw")
    groups.append(("back-face hits (triangles are two-sided)", items))

    items = [
        ("parallel, above the plane, heading across the triangle", [-5, 1, 1, 1, 0, 0] + [x for p in T for x in p], "mc"),
        ("parallel, below the plane, oblique in-plane direction", [-5, -5, -2, 1, 1, 0] + [x for p in T for x in p], "mc"),
        ("parallel, non-unit direction", [10, 10, 0.5, -3, -2.5, 0] + [x for p in T for x in p], "mc"),
        ("parallel to a tilted triangle (d = e1 exactly)", [0, 0, 5, 1, 2, 3, 1, 0, 0, 2, 2, 3, 1, 1, 1], "mc"),
    ]
    groups.append(("rays parallel to the triangle plane (det = 0 exactly; miss).  Filter (a) cannot hold for det = 0;"
                   " instead 400 random 2-ulp perturbations are checked to stay misses", items))

    items = [
        ("triangle behind the origin, axis-aligned", [1, 1, 5, 0, 0, 1] + [x for p in T for x in p], "raw"),
        ("triangle behind, oblique", [2, 1, 3] + [-x for x in aim((2, 1, 3), T, 0.2, 0.3)] + [x for p in T for x in p], "raw"),
        ("triangle behind, from below", [1, 0.5, -4, 0, 0, -2] + [x for p in T for x in p], "raw"),
    ]
    groups.append(("triangle behind the origin (miss)", items))

    L = (( -1e5, -1e5, 2e5), (3e5, -5e4, 2.5e5), (-5e4, 4e5, 1.5e5))
    Lf = tuple(v32(p) for p in L)
    items = []
    for u, v, tag in ((0.3, 0.3, "hit"), (0.05, 0.9, "hit"), (0.6, 0.5, "miss (u+v>1)"), (-0.05, 0.5, "miss (u<0)")):
        o = (1000.0, -2000.0, 500.0)
        items.append(("large triangle (~1e5), origin near 0, %s" % tag, list(o) + aim(o, Lf, u, v) + [x for p in Lf for x in p], "raw"))
    o = (3e5, 2e5, -1e5)
    items.append(("large triangle, origin ~3e5 away, hit", list(o) + aim(o, Lf, 0.4, 0.2) + [x for p in Lf for x in p], "raw"))
    S = ((1e-3, 2e-3, 0.0), (3e-3, 1.5e-3, 5e-4), (1.5e-3, 4e-3, -5e-4))
    Sf = tuple(v32(p) for p in S)
    for u, v, tag in ((0.3, 0.3, "hit"), (0.7, 0.2, "hit"), (0.5, 0.6, "miss (u+v>1)"), (0.4, -0.1, "miss (v<0)")):
        o = (0.0, 0.0, 0.01)
        items.append(("tiny triangle (~2e-3) near the origin, %s" % tag, list(o) + aim(o, Sf, u, v) + [x for p in Sf for x in p], "raw"))
    o = (0.004, 0.001, -0.003)
    items.append(("tiny triangle, origin on the other side, non-unit |d| = 1e-3", list(o) + aim(o, Sf, 0.2, 0.5, 1e-3) + [x for p in Sf for x in p], "raw"))
    groups.append(("large and tiny triangles", items))

    body = []
    allcases = []
    for title, items in groups:
        body.append("# --- %s ---" % title)
        for name, xs, cond in items:
            st = Stats()
            if cond == "mc":
                xs32 = [f32(float(x)) for x in xs]
                res = triangle_eval(xs32)
                assert res.flag is not None and not res.hit
                if not mc_robust("triangle", xs32, trials=400):
                    dropped.append((title, name, "MC"))
                    continue
            else:
                res = accept("triangle", [float(x) for x in xs], st, cond=cond)
                if res is None:
                    dropped.append((title, name, str(st)))
                    continue
            body.append("# " + name + ("" if not res.hit else "  [%s face]" % ("front" if res.front else "back")))
            body.append(case_line(res))
            allcases.append(res)
        body.append("")
    lines = header("triangle", fname, [
        "hand-picked structure cases: coordinates offset by 1e4, back-face hits, rays parallel to",
        "the triangle plane, triangle behind the origin, large (~1e5) and tiny (~1e-3) triangles.",
        "Offset-1e4 cases: filter (a) on the raw inputs; filter (b) on the translated inputs",
        "(o-a, d, 0, b-a, c-a), which are exact f32 (Sterbenz), since an absolute 2-ulp move of",
        "coordinates ~1e4 (~2e-3) would otherwise swamp t, u, v of a triangle a few units wide.",
        "'front face' means d.((b-a)x(c-a)) < 0.",
        count_note(allcases),
    ])
    write_file(fname, lines + body, allcases)
    return dropped


# ---------------------------------------------------------------------------
# triangle_bad.txt
# ---------------------------------------------------------------------------

TRI_FIELDS = ["ox", "oy", "oz", "dx", "dy", "dz", "ax", "ay", "az", "bx", "by", "bz", "cx", "cy", "cz"]


def gen_triangle_bad():
    T = [0, 0, 0, 4, 0, 0, 0, 3, 0]
    base = [1, 1, 5, 0, 0, -1] + T
    extra = [
        ("degenerate triangles (zero area)", [
            ("a = b", [1, 1, 5, 0, 0, -1, 0, 0, 0, 0, 0, 0, 0, 3, 0]),
            ("b = c", [1, 1, 5, 0, 0, -1, 0, 0, 0, 4, 0, 0, 4, 0, 0]),
            ("a = c", [1, 0, 5, 0, 0, -1, 0, 0, 0, 4, 0, 0, 0, 0, 0]),
            ("a = b = c", [0, 0, 5, 0, 0, -1, 0, 0, 0, 0, 0, 0, 0, 0, 0]),
            ("collinear on the x axis, ray through the segment", [1, 0, 5, 0, 0, -1, 0, 0, 0, 4, 0, 0, 2, 0, 0]),
            ("collinear, oblique line (1,2,3) t", [0.5, 1, 10, 0, 0, -1, 0, 0, 0, 1, 2, 3, 2, 4, 6]),
            ("collinear (c = midpoint of ab), ray through c", [-1, 1, 1, 1, 0, 0, 0, 0, 0, 2, 2, 2, 1, 1, 1]),
            ("collinear: a = 0, b = f32(0.1, 0.2, 0.3), c = 2 b exactly; ray through the segment", [0.1, 0.2, 1, 0, 0, -1, 0, 0, 0, 0.1, 0.2, 0.3, 0.2, 0.4, 0.6]),
        ]),
        ("ray in the triangle's plane (det = 0 exactly; the line crosses the triangle)", [
            ("in the plane z = 0, crossing the triangle", [-5, 1, 0, 1, 0, 0] + T),
            ("origin inside the triangle, in-plane direction", [1, 1, 0, 0, 1, 0] + T),
        ]),
        ("origin on the triangle: t = 0 exactly, not in the open interval", [
            ("origin at an interior point, ray leaving the face", [1, 1, 0, 0, 0, 1] + T),
            ("origin at vertex a, oblique ray", [0, 0, 0, 1, 1, 1] + T),
        ]),
        ("zero direction", [
            ("d = (0,0,0), origin above the triangle", [1, 1, 5, 0, 0, 0] + T),
            ("d = (0,0,0), origin in the triangle", [1, 1, 0, 0, 0, 0] + T),
            ("d = (-0,-0,-0)", [1, 1, 5, -0.0, -0.0, -0.0] + T),
        ]),
        ("all non-finite / mixed", [
            ("every field NaN", [NAN] * 15),
            ("direction (0, 0, -inf)", [1, 1, 5, 0, 0, -INF] + T),
            ("vertex a at +inf (all coordinates)", [1, 1, 5, 0, 0, -1, INF, INF, INF, 4, 0, 0, 0, 3, 0]),
            ("origin at -inf, pointing up", [1, 1, -INF, 0, 0, 1] + T),
        ]),
    ]
    bad_file("triangle", "triangle_bad.txt",
             ["bad / degenerate triangle inputs: zero-area triangles (equal or collinear vertices), ray in",
              "the triangle's plane (det = 0), origin on the triangle (t = 0 is outside the open interval),",
              "zero direction, NaN/inf in every field."],
             base, TRI_FIELDS, list(range(15)), extra)


# ---------------------------------------------------------------------------
# accuracy classes (issue 10): hard but decidable cases with recorded conditioning
# ---------------------------------------------------------------------------
#
# Each file is one class of the accuracy table (tests/suite/accuracy.rs, README).  Filter (a)
# applies as everywhere; filter (b) does not: each hit records its conditioning after `~`
# (see cond_values and README.md), so a checker can size a per-case tolerance and the
# accuracy test can report errors relative to it.

ACC_FILTER_TEXT = [
    "Filters: (a) decidable at 2 ulps, as in the other files (exact gradients of every decision",
    "  quantity; 16 random 2-ulp perturbations re-classify identically).  (b) is NOT applied: these",
    "  cases are hard on purpose.  Instead every hit records its conditioning after `~`, one number",
    "  per expected value: for t the relative change a 2-ulp move of the inputs can cause (first",
    "  order: sum_i |dt/dx_i| 2 ulp_f32(x_i) / |t|), for u and v the absolute change.",
]
ACC_TRANSLATED_TEXT = [
    "  Conditioning here is measured on the translated inputs (o-c, d, 0, r / o-a, d, 0, b-a, c-a /",
    "  o-p, d, 0, n), which are exact f32 (Sterbenz): every method computes these differences",
    "  exactly, so an absolute 2-ulp move of coordinates ~1e5 (~0.016) is not what it sees.",
    "conditioning: translated",
]


def acc_file(kind, fname, title, strata, make, cond="report", per_case_note=None):
    """Generate one accuracy class.  strata: list of (label, param, n_hit, n_miss); make(rng,
    param, want_hit, idx) returns the raw inputs (doubles; rounded to f32 by accept) or None.
    Cases whose exact classification differs from the wanted one are dropped (counted)."""
    rng = random.Random(SEEDS[fname])
    blocks = []
    allcases = []
    stats = []
    idx = 0
    for label, param, n_hit, n_miss in strata:
        st = Stats()
        got = {True: [], False: []}
        quota = {True: n_hit, False: n_miss}
        tries = 0
        while len(got[True]) < n_hit or len(got[False]) < n_miss:
            tries += 1
            assert tries < 200 * (n_hit + n_miss), (fname, label, str(st))
            # interleave hits and misses in the stratum's proportion
            want = len(got[True]) * n_miss <= len(got[False]) * n_hit
            if len(got[True]) >= quota[True]:
                want = False
            if len(got[False]) >= quota[False]:
                want = True
            idx += 1
            xs = make(rng, param, want, idx)
            if xs is None:
                st.tried += 1
                st.reject("construction")
                continue
            res = accept(kind, xs, st, cond=cond)
            if res is None:
                continue
            if res.hit != want:
                st.kept -= 1
                st.reject("landed on the other side")
                continue
            res.record = True
            got[want].append(res)
        cases = got[True] + got[False]
        stats.append((label, st))
        blk = ["# --- %s: %s ---" % (label, count_note(cases)), "#   candidates: %s" % st]
        if per_case_note:
            blk.append("#   " + per_case_note(cases))
        blk += [case_line(r) for r in cases]
        blk.append("")
        blocks.append(blk)
        allcases += cases
    extra = ACC_FILTER_TEXT + (ACC_TRANSLATED_TEXT if cond.endswith("translated") else [])
    lines = header(kind, fname, title + [count_note(allcases)], filters=False, extra=extra)
    for blk in blocks:
        lines += blk
    write_file(fname, lines, allcases)
    return stats


def cond_range(cases):
    ts = [float(cond_values(c)[0]) for c in cases if c.hit]
    if not ts:
        return "no hits"
    return "t conditioning (relative) from %.2g to %.2g" % (min(ts), max(ts))


def uv_range(cases):
    hs = [c for c in cases if c.hit]
    if not hs:
        return "no hits"
    ts = [float(cond_values(c)[0]) for c in hs]
    uv = [max(float(x) for x in cond_values(c)[1:]) for c in hs]
    return "conditioning: t (relative) %.2g..%.2g, u/v (absolute) %.2g..%.2g" % (min(ts), max(ts), min(uv), max(uv))


def mp_cos(x):
    return float(mp.cos(x))


def mp_sin(x):
    return float(mp.sin(x))


def tilted(rng, w, g):
    """Unit vector at cos g from the unit vector w (random azimuth), random sign."""
    e = rand_perp(rng, w)
    s = math.sqrt(max(0.0, 1.0 - g * g))
    n = vunit(vadd(vscale(g, w), vscale(s, e)))
    return n if rng.random() < 0.5 else vscale(-1.0, n)


def plane_frame(rng, n):
    e1 = rand_perp(rng, n)
    return e1, vunit(vcross(n, e1))


def shaped_triangle(rng, P, n, size):
    """A well-shaped triangle around P in the plane with normal n: vertices at angles
    ~120 degrees apart (jitter +-0.4 rad), at 0.6..1 x size from P; f32 vertices."""
    e1, e2 = plane_frame(rng, n)
    phi = rng.uniform(0, 2 * math.pi)
    vs = []
    for k in range(3):
        a = phi + k * 2 * math.pi / 3 + rng.uniform(-0.4, 0.4)
        rho = size * rng.uniform(0.6, 1.0)
        vs.append(v32(vadd(P, vadd(vscale(rho * mp_cos(a), e1), vscale(rho * mp_sin(a), e2)))))
    if rng.random() < 0.5:
        vs[1], vs[2] = vs[2], vs[1]
    return vs


def aim_uv(rng, want_hit, idx):
    """Barycentrics (u, v) of the aim point: uniform over the triangle for a hit, or a distance
    delta (log-uniform in [1e-3, 0.3], barycentric units) outside one of the three edges."""
    if want_hit:
        u, v = rng.random(), rng.random()
        if u + v > 1:
            u, v = 1 - u, 1 - v
        return u, v
    delta = loguniform(rng, 1e-3, 0.3)
    s = rng.random()
    edge = idx % 3
    if edge == 0:
        return -delta, s
    if edge == 1:
        return s, -delta
    return s * (1 + delta), (1 - s) * (1 + delta)


def tri_case(rng, o, tri, want_hit, idx):
    u, v = aim_uv(rng, want_hit, idx)
    Q = tri_point(*tri, u, v)
    dv = vsub(Q, o)
    if vnorm(dv) == 0:
        return None
    d = dir32(rng, dv, idx % 2 == 0)
    return list(o) + list(d) + [x for p in tri for x in p]


def gen_triangle_far():
    def make(rng, k, want, idx):
        o = (0.0, 0.0, 0.0) if rng.random() < 0.25 else v32(rand_box(rng, 1))
        size = loguniform(rng, 0.05, 5.0)
        c = size * float(mp.power(2, k + rng.random()))
        w = rand_unit(rng)
        n = tilted(rng, w, rng.uniform(0.1, 1.0))
        tri = shaped_triangle(rng, vadd(o, vscale(c, w)), n, size)
        return tri_case(rng, o, tri, want, idx)
    strata = [("c/l in [2^%d, 2^%d)" % (k, k + 1), k, 18, 7) for k in range(4, 12)]
    return acc_file("triangle", "triangle_far.txt", [
        "accuracy class 'far': small triangles far from the ray origin, c/l from 2^4 to 2^12 (c: the",
        "distance to the triangle's centre, l: its circumradius, log-uniform in [0.05, 5]); well-shaped",
        "triangles, cos(angle between the view direction and the normal) uniform in [0.1, 1]; origin 0",
        "(25%) or uniform in [-1,1]^3; directions alternate unit / non-unit.  Hits aim at a uniform",
        "point of the triangle, misses at a point 1e-3..0.3 (barycentric) outside an edge.",
    ], strata, make, per_case_note=uv_range)


def gen_triangle_needle():
    def make(rng, decade, want, idx):
        o = (0.0, 0.0, 0.0) if rng.random() < 0.25 else v32(rand_box(rng, 1))
        aspect = float(mp.power(10, decade + rng.random() * 0.5))
        L = loguniform(rng, 0.5, 5.0)
        dist = rng.uniform(1.0, 10.0)
        w = rand_unit(rng)
        n = tilted(rng, w, rng.uniform(0.2, 1.0))
        P = vadd(o, vscale(dist, w))
        e1, e2 = plane_frame(rng, n)
        s = rng.uniform(-0.5, 0.5)
        A = vadd(P, vscale(-L / 2, e1))
        B = vadd(P, vscale(L / 2, e1))
        C = vadd(P, vadd(vscale(s * L, e1), vscale(L / aspect, e2)))
        tri = [v32(A), v32(B), v32(C)]
        k = idx % 3
        tri = tri[k:] + tri[:k]
        return tri_case(rng, o, tri, want, idx)
    strata = [("aspect ratio in [10^%.1f, 10^%.1f)" % (d, d + 0.5), d, 25, 8)
              for d in (1.0, 1.5, 2.0, 2.5, 3.0, 3.5)]
    return acc_file("triangle", "triangle_needle.txt", [
        "accuracy class 'needle': needle-shaped triangles, aspect ratio (long edge / height) from 10",
        "to 10^4; long edge log-uniform in [0.5, 5], 1..10 from the origin, cos(view, normal) in",
        "[0.2, 1]; the apex sits anywhere along the long edge and the vertex order is rotated.",
        "Hits aim at a uniform point, misses 1e-3..0.3 (barycentric) outside an edge.",
    ], strata, make, per_case_note=uv_range)


def gen_triangle_grazing():
    def make(rng, e, want, idx):
        o = (0.0, 0.0, 0.0) if rng.random() < 0.25 else v32(rand_box(rng, 1))
        g = float(mp.power(2, -e - rng.random()))
        size = loguniform(rng, 0.5, 4.0)
        dist = size * rng.uniform(1.0, 16.0)
        w = rand_unit(rng)
        n = tilted(rng, w, g)
        tri = shaped_triangle(rng, vadd(o, vscale(dist, w)), n, size)
        args = tri_case(rng, o, tri, want, idx)
        if args is None:
            return None
        # keep the stratum: the actual cos between the ray and the normal
        d = args[3:6]
        nn = vunit(vcross(vsub(tri[1], tri[0]), vsub(tri[2], tri[0])))
        cg = abs(vdot(vunit(d), nn))
        if not 2.0 ** (-e - 1) <= cg < 2.0 ** (-e + 0.25):
            return None
        return args
    strata = [("cos in [2^-%d, 2^-%d)" % (e + 1, e), e, 15, 5) for e in range(0, 10)]
    return acc_file("triangle", "triangle_grazing.txt", [
        "accuracy class 'grazing': rays nearly parallel to the triangle, cos(ray, normal) from 1 down",
        "to 2^-10 (the stratum is checked on the actual ray); well-shaped triangles of circumradius",
        "0.5..4 at 1..16 x that from the origin.  Hits aim at a uniform point, misses 1e-3..0.3",
        "(barycentric) outside an edge.",
    ], strata, make, per_case_note=uv_range)


def gen_triangle_offset():
    OFF = (1e5, 1e5, 1e5)

    def make(rng, _p, want, idx):
        base = vadd(OFF, rand_box(rng, 100))
        size = loguniform(rng, 0.5, 8.0)
        dist = rng.uniform(1.0, 50.0)
        w = rand_unit(rng)
        o = v32(base)
        n = tilted(rng, w, rng.uniform(0.2, 1.0))
        tri = shaped_triangle(rng, vadd(o, vscale(dist, w)), n, size)
        return tri_case(rng, o, tri, want, idx)
    strata = [("offset 1e5", None, 150, 50)]
    return acc_file("triangle", "triangle_offset.txt", [
        "accuracy class 'offset': large coordinates.  Origin and triangle near (1e5, 1e5, 1e5) (within",
        "+-150), the triangle small (circumradius 0.5..8, f32 vertices on the 2^-7 grid of 1e5) and",
        "1..50 from the origin, cos(view, normal) in [0.2, 1].",
    ], strata, make, cond="report-translated", per_case_note=uv_range)


def gen_triangle_grid():
    def grid(rng):
        eye = v32(rand_box(rng, 1))
        w = rand_unit(rng)
        n = tilted(rng, w, rng.uniform(0.62, 1.0))
        D = rng.uniform(3.0, 5.0)
        s = rng.uniform(0.06, 0.085)
        e1, e2 = plane_frame(rng, n)
        return eye, vadd(eye, vscale(D, w)), s, e1, e2

    state = {}

    def make(rng, g, want, idx):
        if state.get("g") != g:
            state["g"] = g
            state["grid"] = grid(rng)
        eye, G, s, e1, e2 = state["grid"]
        i, j = rng.randint(-12, 11), rng.randint(-12, 11)

        def V(a, b):
            return v32(vadd(G, vadd(vscale(a * s, e1), vscale(b * s, e2))))
        tris = [[V(i, j), V(i + 1, j), V(i + 1, j + 1)], [V(i, j), V(i + 1, j + 1), V(i, j + 1)]]
        k = rng.randint(0, 1)
        u, v = rng.random(), rng.random()
        if u + v > 1:
            u, v = 1 - u, 1 - v
        Q = tri_point(*tris[k], u, v)
        tri = tris[k] if want else tris[1 - k]
        d = dir32(rng, vsub(Q, eye), idx % 2 == 0)
        nn = vunit(vcross(vsub(tri[1], tri[0]), vsub(tri[2], tri[0])))
        if not abs(vdot(vunit(d), nn)) >= 0.59:
            return None
        return list(eye) + list(d) + [x for p in tri for x in p]
    strata = [("grid %d" % g, g, 15, 5) for g in range(10)]
    return acc_file("triangle", "triangle_grid.txt", [
        "accuracy class 'grid': planar grids seen at an angle, as in Embree's watertightness test plane.",
        "Per block one grid: square cells 0.06..0.085 wide (two triangles each, f32 grid points), its",
        "centre 3..5 from an eye in [-1,1]^3, cos(ray, normal) from 0.59 to 1 (checked per ray); cells",
        "within 12 of the centre.  A hit aims at a uniform point of one triangle of a cell; a miss is",
        "the same ray against the cell's other triangle (so its nearest edge is the shared diagonal).",
    ], strata, make, per_case_note=uv_range)


def sphere_aim(rng, o, C, r, lr, unit):
    """Unit/non-unit f32 direction from o whose line passes at distance lr * r from C."""
    w = vsub(C, o)
    c = vnorm(w)
    w = vunit(w)
    sa = lr * r / c
    if sa >= 1:
        return None
    e = rand_perp(rng, w)
    dv = vadd(vscale(math.sqrt(1 - sa * sa), w), vscale(sa, e))
    return list(dir32(rng, dv, unit))


def gen_sphere_grazing():
    def make(rng, e, want, idx):
        r = loguniform(rng, 0.1, 10.0)
        k = rng.uniform(1, 8)
        o = v32(rand_box(rng, 10))
        C = v32(vadd(o, vscale(r * float(mp.power(2, k)), rand_unit(rng))))
        delta = float(mp.power(2, -e - 2 * rng.random()))
        lr = 1 - delta if want else 1 + delta
        d = sphere_aim(rng, o, C, r, lr, idx % 2 == 0)
        return None if d is None else list(o) + d + list(C) + [r]
    strata = [("|1 - l/r| in [2^-%d, 2^-%d)" % (e + 2, e), e, 15, 5) for e in range(2, 20, 2)]
    return acc_file("sphere", "sphere_grazing.txt", [
        "accuracy class 'grazing': near-tangent rays.  The ray passes at l = (1 -+ delta) r from the",
        "centre, delta from 2^-2 down to 2^-20 (cos of the incidence angle down to ~2^-10); r",
        "log-uniform in [0.1, 10], c/r = 2^U(1,8), origin in [-10,10]^3; directions alternate unit /",
        "non-unit.  Hits (l < r) and misses (l > r) per stratum; filter (a) drops the undecidable.",
    ], strata, make, per_case_note=cond_range)


def gen_sphere_offset():
    OFF = (1e5, 1e5, 1e5)

    def make(rng, _p, want, idx):
        C = v32(vadd(OFF, rand_box(rng, 100)))
        r = loguniform(rng, 0.5, 8.0)
        if want and rng.random() < 0.15:       # origin inside
            o = v32(vadd(C, vscale(r * rng.uniform(0, 0.9), rand_unit(rng))))
            return list(o) + list(dir32(rng, rand_unit(rng), idx % 2 == 0)) + list(C) + [r]
        o = v32(vadd(C, vscale(r * float(mp.power(2, rng.uniform(1, 6))), rand_unit(rng))))
        lr = rng.uniform(0, 0.98) if want else rng.uniform(1.02, 1.5)
        d = sphere_aim(rng, o, C, r, lr, idx % 2 == 0)
        return None if d is None else list(o) + d + list(C) + [r]
    strata = [("offset 1e5", None, 120, 40)]
    return acc_file("sphere", "sphere_offset.txt", [
        "accuracy class 'offset': large coordinates.  Centre near (1e5, 1e5, 1e5) (within +-100), r",
        "log-uniform in [0.5, 8], origin at 2^U(1,6) r from the centre (15% of the hits from inside);",
        "the line passes at l/r uniform in [0, 0.98] (hit) or [1.02, 1.5] (miss).",
    ], strata, make, cond="report-translated", per_case_note=cond_range)


def sphere_scaled(lo, hi):
    def make(rng, _p, want, idx):
        r = float(mp.power(2, rng.uniform(lo, hi)))
        o = v32(rand_box(rng, 64 * r))
        C = v32(vadd(o, vscale(r * float(mp.power(2, rng.uniform(1, 6))), rand_unit(rng))))
        lr = rng.uniform(0, 0.98) if want else rng.uniform(1.02, 1.5)
        d = sphere_aim(rng, o, C, r, lr, idx % 2 == 0)
        return None if d is None else list(o) + d + list(C) + [r]
    return make


def gen_sphere_tiny():
    out = [("r in [2^%d, 2^%d)" % (e, e + 4), e, 15, 5) for e in range(-24, -8, 4)]

    def mk(rng, lo, want, idx):
        return sphere_scaled(lo, lo + 4)(rng, None, want, idx)
    return acc_file("sphere", "sphere_tiny.txt", [
        "accuracy class 'tiny r': small spheres, r = 2^U(-24,-8), scenes scaled with r: origin in",
        "[-64 r, 64 r]^3, centre at 2^U(1,6) r from it, l/r uniform in [0, 0.98] (hit) or",
        "[1.02, 1.5] (miss); directions alternate unit / non-unit.",
    ], out, mk, per_case_note=cond_range)


def gen_sphere_huge():
    out = [("r in [2^%d, 2^%d)" % (e, e + 4), e, 15, 5) for e in range(8, 24, 4)]

    def mk(rng, lo, want, idx):
        return sphere_scaled(lo, lo + 4)(rng, None, want, idx)
    return acc_file("sphere", "sphere_huge.txt", [
        "accuracy class 'huge r': large spheres, r = 2^U(8,24), scenes scaled with r: origin in",
        "[-64 r, 64 r]^3, centre at 2^U(1,6) r from it, l/r uniform in [0, 0.98] (hit) or",
        "[1.02, 1.5] (miss); directions alternate unit / non-unit.",
    ], out, mk, per_case_note=cond_range)


def plane_case(rng, o, w, n, T, want, idx):
    """The ray from o along the unit w against the plane with unit normal n through a point at
    T along the ray (at -T, behind the origin, for a miss), moved by up to 5 within the plane;
    directions and normals alternate unit / non-unit."""
    e1, e2 = plane_frame(rng, n)
    p = vadd(vadd(o, vscale(T if want else -T, w)), vadd(vscale(rng.uniform(-5, 5), e1), vscale(rng.uniform(-5, 5), e2)))
    d = dir32(rng, w, idx % 2 == 0)
    nn = dir32(rng, n, (idx // 2) % 2 == 0)
    return list(o) + list(d) + list(v32(p)) + list(nn)


def gen_plane_grazing():
    def make(rng, e, want, idx):
        o = v32(rand_box(rng, 10))
        w = rand_unit(rng)
        g = float(mp.power(2, -e - rng.random()))
        n = tilted(rng, w, g)
        return plane_case(rng, o, w, n, rng.uniform(1.0, 20.0), want, idx)
    strata = [("cos in [2^-%d, 2^-%d)" % (e + 1, e), e, 8, 2) for e in range(0, 10)]
    return acc_file("plane", "plane_grazing.txt", [
        "accuracy class 'grazing': rays nearly parallel to the plane, cos(ray, normal) from 1 down to",
        "2^-10; origin in [-10,10]^3, the plane 1..20 along the ray (behind it for the misses), its",
        "point offset by up to 5 in the plane; normals and directions alternate unit / non-unit.",
    ], strata, make, per_case_note=cond_range)


def gen_plane_offset():
    OFF = (1e5, 1e5, 1e5)

    def make(rng, _p, want, idx):
        o = v32(vadd(OFF, rand_box(rng, 100)))
        w = rand_unit(rng)
        n = tilted(rng, w, rng.uniform(0.1, 1.0))
        return plane_case(rng, o, w, n, rng.uniform(1.0, 50.0), want, idx)
    strata = [("offset 1e5", None, 60, 20)]
    return acc_file("plane", "plane_offset.txt", [
        "accuracy class 'offset': large coordinates.  Origin and plane point near (1e5, 1e5, 1e5)",
        "(within +-150), the plane 1..50 along the ray (behind it for the misses), cos(ray, normal)",
        "uniform in [0.1, 1]; normals and directions alternate unit / non-unit.",
    ], strata, make, cond="report-translated", per_case_note=cond_range)


# ---------------------------------------------------------------------------

def main():
    t0 = time.time()
    os.makedirs(OUT_DIR, exist_ok=True)
    report = []
    checks = gen_sphere_lecture()
    report.append("sphere_lecture: closed forms vs f32 expectations")
    for o, dn, cv, res in checks:
        report.append("  o=%s d=%s closed=%s got=%s" % (o, dn, [mp.nstr(x, 10) for x in cv], [fmt32(x) for x in res.out]))
    st = gen_sphere_random()
    report.append("sphere_random: " + str(st))
    per_k = gen_sphere_far()
    for k, (kst, rr, cases) in sorted(per_k.items()):
        report.append("sphere_far k=%2d: uniform %s | rim %s | rim |1-l/r| range [%.3g, %.3g]" % (
            k, kst["uniform"], kst["rim"], rr["rim-in"][0], rr["rim-in"][1]))
    st, maxrel = gen_sphere_ground()
    report.append("sphere_ground: " + str(st) + "; max rel. sensitivity of t0 per R: " +
                  ", ".join("%g: %s" % (R, fmt_sci(v)) for R, v in sorted(maxrel.items())))
    dropped = gen_sphere_special()
    report.append("sphere_special dropped: %s" % (dropped or "none"))
    gen_sphere_bad()
    st, stp = gen_plane_random()
    report.append("plane_random: " + str(st) + " | nearly parallel: " + str(stp))
    gen_plane_bad()
    st = gen_triangle_random()
    report.append("triangle_random: " + str(st))
    dropped = gen_triangle_special()
    report.append("triangle_special dropped: %s" % (dropped or "none"))
    gen_triangle_bad()
    for gen in (gen_triangle_far, gen_triangle_needle, gen_triangle_grazing, gen_triangle_offset,
                gen_triangle_grid, gen_sphere_grazing, gen_sphere_offset, gen_sphere_tiny,
                gen_sphere_huge, gen_plane_grazing, gen_plane_offset):
        for label, st in gen():
            report.append("%s %s: %s" % (gen.__name__[4:], label, st))
    for line in report:
        print(line)
    print()
    for fname, n, h, m in SUMMARY:
        print("%-22s %4d cases  %4d hits  %4d misses" % (fname, n, h, m))
    print("total time %.1f s" % (time.time() - t0))


if __name__ == "__main__":
    main()
