"""The headline of a comparison: each method's factor against the path tracer, raw and denoised.

"ReSTIR PT is 14x better raw and 1.4x worse denoised" as one line to read. At equal time the
baseline of a method is the path tracer at that method's frame time (equal_time.py), so that
per frame both had the same time: a frame worth s path-tracer samples is compared with the path
tracer's errors at the whole spp on both sides of s, interpolated log-log in spp (an error of n
independent samples falls as a power of n). Otherwise (equal samples or frames, or matching off)
the baseline is the first `pt` method given. A factor is the baseline's relMSE over the method's:
above 1 the method's error is lower.
"""
import math


def factor_text(factor) -> str:
    if factor is None:
        return "-"
    return f"{factor:.2f}x lower" if factor >= 1 else f"{1 / factor:.2f}x higher"


def at_spp(lo, hi, spp: float, key: str):
    """The path tracer's metric `key` at `spp` from its results lo and hi at whole spp around it:
    log-log between them (linear where a value is not positive); None where either lacks it."""
    a, b = lo.metrics.get(key), hi.metrics.get(key)
    if a is None or b is None:
        return None
    if hi.spp == lo.spp:
        return a
    t = math.log(spp / lo.spp) / math.log(hi.spp / lo.spp)
    if a > 0 and b > 0:
        return math.exp((1 - t) * math.log(a) + t * math.log(b))
    return (1 - t) * a + t * b


def _over(value, method, key):
    b = method.metrics.get(key)
    return value / b if value is not None and b else None


KEYS = ("relmse_frame", "relmse_denoised_frame", "relmse_accumulated")


def _at_frame_time(matched, spp):
    """The path tracer at `spp` from its results at the whole spp around it: the label nearest
    spp, the text's name, ms per frame and the metrics (interpolated when there are two)."""
    lo, hi = matched[0], matched[-1]
    base = min(matched, key=lambda p: abs(p.spp - spp))
    if lo is hi:
        return base, base.label, base.metrics["ms_per_frame"], {k: base.metrics.get(k) for k in KEYS}
    t = (spp - lo.spp) / (hi.spp - lo.spp)  # frame time is linear in spp
    ms = (1 - t) * lo.metrics["ms_per_frame"] + t * hi.metrics["ms_per_frame"]
    name = f"the path tracer at {spp:.2f} spp, {lo.label} and {hi.label} interpolated"
    return base, name, ms, {k: at_spp(lo, hi, spp, k) for k in KEYS}


def headline(comparison) -> list:
    """One dict per non-pt method with a baseline: method, baseline (the path tracer's label; at
    equal time the one nearer the method's frame), baseline_spp (equal time: the method's frame in
    path-tracer spp; None otherwise), basis, ms_per_frame of both, the factors raw_frame,
    denoised_frame (None without denoising) and accumulated, and text."""
    pts = [m for m in comparison.methods if m.method == "pt"]
    spp_of = (comparison.frame_time_fit or {}).get("spp_of", {})
    out = []
    for m in comparison.methods:
        if m.method == "pt":
            continue
        matched = sorted((p for p in pts if m.label in p.frame_time_of), key=lambda p: p.spp)
        if matched:
            spp, basis = spp_of.get(m.label, float(matched[0].spp)), "equal frame time"
            base, name, ms, value = _at_frame_time(matched, spp)
        elif pts:
            base, basis, spp = pts[0], comparison.budget.split(":")[0], None
            name, ms, value = base.label, base.metrics["ms_per_frame"], {k: base.metrics.get(k) for k in KEYS}
        else:
            continue
        entry = {"method": m.label, "baseline": base.label, "baseline_spp": spp, "basis": basis,
                 "ms_per_frame": [m.metrics["ms_per_frame"], ms],
                 "raw_frame": _over(value["relmse_frame"], m, "relmse_frame"),
                 "denoised_frame": _over(value["relmse_denoised_frame"], m, "relmse_denoised_frame"),
                 "accumulated": _over(value["relmse_accumulated"], m, "relmse_accumulated")}
        entry["text"] = (f"{m.label} against {name} ({basis}, {entry['ms_per_frame'][0]:.1f} vs "
                         f"{entry['ms_per_frame'][1]:.1f} ms per frame): per-frame relMSE raw "
                         f"{factor_text(entry['raw_frame'])}, denoised {factor_text(entry['denoised_frame'])}; "
                         f"accumulated {factor_text(entry['accumulated'])}")
        out.append(entry)
    return out
