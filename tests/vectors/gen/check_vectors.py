#!/usr/bin/env python3
# Independent self-check of the raylane test vectors.
#
#     python3 tests/vectors/gen/check_vectors.py
#
# Re-parses every tests/vectors/*.txt file and, independently of
# gen_vectors.py (no Fractions, no mpmath: plain IEEE double formulas),
#   * checks the line grammar and that every number field is written as the
#     shortest decimal that round-trips to an f32 value;
#   * re-classifies each case (hit/miss and the number of sphere roots) and
#     re-computes t (and u, v) in double precision; the expected value must
#     agree to within half an f32 ulp (its own rounding) + 1e-9 relative
#     (t) / 1e-9 absolute (u, v);
#   * checks the conditioning recorded after `~` (one number per expected value)
#     against 2-ulp finite differences of the same double formulas: the sum
#     over the inputs of |change| must agree within a factor of 2.
# Exits non-zero on any failure.
"""Self-check for the raylane test vectors (see README.md)."""

import glob
import math
import os
import re
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
VEC_DIR = os.path.dirname(HERE)

NUM_RE = re.compile(r"^-?(0|[1-9][0-9]*)(\.[0-9]*[1-9])?(e-?[1-9][0-9]*)?$|^-?0\.[0-9]*[1-9](e-?[1-9][0-9]*)?$")
NIN = {"sphere": 10, "plane": 12, "triangle": 15}
NOUT = {"sphere": (0, 1, 2), "plane": (0, 1), "triangle": (0, 3)}


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def ulp32(x):
    x = abs(x)
    if x < 2.0 ** -126:
        return 2.0 ** -149
    return 2.0 ** (math.frexp(x)[1] - 24)


def sig_digits(s):
    m = s.lstrip("-").split("e")[0].replace(".", "").lstrip("0")
    return len(m.rstrip("0")) if m else 1


def parse_num(s, errs, where):
    if s == "NaN":
        return float("nan")
    if s == "inf":
        return float("inf")
    if s == "-inf":
        return float("-inf")
    if not NUM_RE.match(s):
        errs.append("%s: bad number spelling %r" % (where, s))
        return float("nan")
    try:
        x = f32(float(s))
    except OverflowError:
        errs.append("%s: %r overflows f32" % (where, s))
        return float("nan")
    if x == 0.0:
        if s.lstrip("-") != "0":
            errs.append("%s: zero not written as 0 / -0: %r" % (where, s))
        return x
    # shortest round trip
    for p in range(1, 10):
        if f32(float("%.*g" % (p, x))) == x:
            break
    if sig_digits(s) != p:
        errs.append("%s: %r is not the shortest round-trip spelling (%d digits, %d needed)" % (where, s, sig_digits(s), p))
    return x


def dot(a, b):
    return math.fsum(x * y for x, y in zip(a, b))


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def cross(a, b):
    return [math.fsum([a[1] * b[2], -a[2] * b[1]]), math.fsum([a[2] * b[0], -a[0] * b[2]]),
            math.fsum([a[0] * b[1], -a[1] * b[0]])]


def finite(xs):
    return all(math.isfinite(x) for x in xs)


def ref_sphere(x):
    o, d, c, r = x[0:3], x[3:6], x[6:9], x[9]
    if not finite(x) or d == [0, 0, 0] or not r > 0:
        return [], None
    w = sub(o, c)
    a = dot(d, d)
    b = dot(d, w)
    tc = -b / a
    f = [wi + tc * di for wi, di in zip(w, d)]
    l = math.sqrt(dot(f, f))
    h2 = (r - l) * (r + l)              # = D / a  (squared half chord)
    ww = math.sqrt(dot(w, w))
    cc = (ww - r) * (ww + r)            # = c'
    margin = min(abs(h2) / (r * r), abs(cc) / (r * r))
    if h2 <= 0:
        return [], margin
    s = math.sqrt(h2 / a)
    if cc < 0:
        return [tc + s], margin
    if tc > 0:
        t1 = tc + s
        return [(cc / a) / t1, t1], margin
    return [], margin


def ref_plane(x):
    o, d, p, n = x[0:3], x[3:6], x[6:9], x[9:12]
    if not finite(x) or d == [0, 0, 0] or n == [0, 0, 0]:
        return [], None
    den = dot(d, n)
    num = dot(sub(p, o), n)
    if den == 0:
        return [], None
    t = num / den
    return ([t] if t > 0 else []), None


def ref_triangle(x):
    o, d, a, b, c = x[0:3], x[3:6], x[6:9], x[9:12], x[12:15]
    if not finite(x) or d == [0, 0, 0]:
        return [], None
    e1, e2, s = sub(b, a), sub(c, a), sub(o, a)
    if cross(e1, e2) == [0, 0, 0]:
        return [], None
    p = cross(d, e2)
    det = dot(e1, p)
    if det == 0:
        return [], None
    q = cross(s, e1)
    u = dot(s, p) / det
    v = dot(d, q) / det
    t = dot(e2, q) / det
    if t > 0 and u >= 0 and v >= 0 and u + v <= 1:
        return [t, u, v], None
    return [], None


REF = {"sphere": ref_sphere, "plane": ref_plane, "triangle": ref_triangle}


def check_file(path):
    errs = []
    name = os.path.basename(path)
    kind_expected = name.split("_")[0]
    lines = open(path).read().split("\n")
    if not lines[0].startswith("# raylane test vectors"):
        errs.append("%s: missing header" % name)
    head = "\n".join(l for l in lines[:30] if l.startswith("#"))
    if "gen_vectors.py" not in head or "random.Random(" not in head and "hand-picked" not in head:
        errs.append("%s: header does not name the generator / seed" % name)
    n = hits = 0
    worst = 0.0
    cond_worst = 0.0
    n_cond = 0
    translated = "# conditioning: translated" in head
    for ln, line in enumerate(lines, 1):
        if not line.strip() or line.startswith("#"):
            continue
        where = "%s:%d" % (name, ln)
        if "->" not in line:
            errs.append("%s: no '->'" % where)
            continue
        lhs, rhs = line.split("->")
        toks = lhs.split()
        kind = toks[0]
        if kind != kind_expected:
            errs.append("%s: kind %r in a %s file" % (where, kind, kind_expected))
            continue
        if len(toks) - 1 != NIN[kind]:
            errs.append("%s: %d inputs, expected %d" % (where, len(toks) - 1, NIN[kind]))
            continue
        xs = [parse_num(s, errs, where) for s in toks[1:]]
        rhs, _, ktext = rhs.partition("~")
        outs = rhs.split()
        if outs == ["miss"]:
            exp = []
        else:
            exp = [parse_num(s, errs, where) for s in outs]
            if not all(math.isfinite(e) for e in exp):
                errs.append("%s: non-finite expectation" % where)
        if len(exp) not in NOUT[kind]:
            errs.append("%s: %d outputs" % (where, len(exp)))
            continue
        n += 1
        hits += bool(exp)
        if name.endswith("_bad.txt") and exp:
            errs.append("%s: hit in a bad-input file" % where)
        got, margin = REF[kind](xs)
        if len(got) != len(exp):
            errs.append("%s: classification differs: expected %s, double reference %s" % (where, outs, got))
            continue
        if ktext:
            conds = [parse_num(s, errs, where) for s in ktext.split()]
            if not exp or len(conds) != len(exp) or not all(k >= 0 for k in conds):
                errs.append("%s: the conditioning needs one nonnegative number per expected value" % where)
            else:
                fd = fd_conditioning(kind, xs, got, translated)
                for i, (k, f) in enumerate(zip(conds, fd)):
                    if not (0.5 * f <= k <= 2 * f or (k == 0 and f == 0)):
                        errs.append("%s: conditioning %d: recorded %g, finite differences %g" % (where, i, k, f))
                    cond_worst = max(cond_worst, abs(math.log2(k / f)) if k and f else 0)
                n_cond += 1
        if margin is not None and margin < 1e-9 and exp:
            errs.append("%s: double reference too close to a decision boundary (%g)" % (where, margin))
        for i, (g, e) in enumerate(zip(got, exp)):
            is_t = kind != "triangle" or i == 0
            tol = 0.5 * ulp32(e) + (1e-9 * abs(e) if is_t else 1e-9)
            dev = abs(g - e)
            if dev > tol:
                errs.append("%s: output %d: expected %r, double reference %r (|diff| %.3g > tol %.3g)" % (where, i, e, g, dev, tol))
            # deviation beyond the f32 rounding, relative to |t| (or absolute for u, v)
            extra = max(0.0, dev - 0.5 * ulp32(e)) / (abs(e) if is_t else 1.0)
            worst = max(worst, extra)
            if is_t and not e > 0:
                errs.append("%s: t <= 0" % where)
        if kind == "sphere" and len(exp) == 2 and not exp[0] <= exp[1]:
            errs.append("%s: roots not ascending" % where)
    return n, hits, worst, (n_cond, cond_worst), errs


def step32(x, k):
    """x moved by k f32 ulps (the f32 spacing at x; 2^-149 at 0)."""
    return x + k * ulp32(x)


def fd_conditioning(kind, xs, got, translated):
    """2-ulp finite-difference conditioning of the outputs: per output, the sum over the inputs
    of the largest |change| when that input moves by +-2 ulps (relative for t, absolute for
    u and v).  With `translated`, the inputs are first translated so that the sphere centre,
    the plane point or vertex a is at the origin (exact in f32 for those files)."""
    xs = list(xs)
    if translated:
        shift = xs[6:9]
        idx = [0, 1, 2, 6, 7, 8] + ([9, 10, 11, 12, 13, 14] if kind == "triangle" else [])
        for i in idx:
            xs[i] = xs[i] - shift[i % 3]
            assert f32(xs[i]) == xs[i]
    tot = [0.0] * len(got)
    for i in range(len(xs)):
        if translated and i in (6, 7, 8):
            continue      # the translated origin is an exact 0, not an input
        ch = [0.0] * len(got)
        for k in (-2, 2):
            ys = list(xs)
            ys[i] = step32(xs[i], k)
            g2, _ = REF[kind](ys)
            if len(g2) != len(got):
                return [float("inf")] * len(got)
            ch = [max(c, abs(a - b)) for c, a, b in zip(ch, g2, got)]
        tot = [t + c for t, c in zip(tot, ch)]
    return [t / abs(g) if kind != "triangle" or j == 0 else t for j, (t, g) in enumerate(zip(tot, got))]


def main():
    files = sorted(glob.glob(os.path.join(VEC_DIR, "*.txt")))
    expected = ["plane_bad.txt", "plane_random.txt", "sphere_bad.txt", "sphere_far.txt", "sphere_ground.txt",
                "sphere_lecture.txt", "sphere_random.txt", "sphere_special.txt", "triangle_bad.txt",
                "triangle_random.txt", "triangle_special.txt",
                # accuracy classes (conditioning recorded after `~`)
                "triangle_far.txt", "triangle_needle.txt", "triangle_grazing.txt", "triangle_offset.txt",
                "triangle_grid.txt", "sphere_grazing.txt", "sphere_offset.txt", "sphere_tiny.txt",
                "sphere_huge.txt", "plane_grazing.txt", "plane_offset.txt"]
    allerrs = []
    names = [os.path.basename(f) for f in files]
    for e in expected:
        if e not in names:
            allerrs.append("missing file " + e)
    total = 0
    for f in files:
        n, h, worst, (nk, kw), errs = check_file(f)
        total += n
        kinfo = ("  conditioning of %d hits within 2^%.2f of finite differences" % (nk, kw)) if nk else ""
        print("%-22s %4d cases  %4d hits  %4d misses  max deviation beyond f32 rounding %.2g%s  %s" % (
            os.path.basename(f), n, h, n - h, worst, kinfo, "OK" if not errs else "%d ERRORS" % len(errs)))
        allerrs += errs
    for e in allerrs[:50]:
        print("ERROR", e)
    print("%d cases checked, %d errors" % (total, len(allerrs)))
    sys.exit(1 if allerrs else 0)


if __name__ == "__main__":
    main()
