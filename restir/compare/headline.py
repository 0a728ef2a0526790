"""The headline of a comparison: each method's factor against the path tracer, raw and denoised.

"ReSTIR PT is 14x better raw and 1.4x worse denoised" as one line to read. At equal time the
baseline of a method is the path tracer at that method's frame time (equal_time.py), so that
per frame both had the same time; otherwise (equal samples or frames, or matching off) the first
`pt` method given. A factor is the baseline's relMSE over the method's: above 1 the method's
error is lower.
"""


def factor_text(factor) -> str:
    if factor is None:
        return "-"
    return f"{factor:.2f}x lower" if factor >= 1 else f"{1 / factor:.2f}x higher"


def _ratio(baseline, method, key):
    a, b = baseline.metrics.get(key), method.metrics.get(key)
    return a / b if a is not None and b else None


def headline(comparison) -> list:
    """One dict per non-pt method with a baseline: method, baseline, basis, ms_per_frame of both,
    the factors raw_frame, denoised_frame (None without denoising) and accumulated, and text."""
    pts = [m for m in comparison.methods if m.method == "pt"]
    out = []
    for m in comparison.methods:
        if m.method == "pt":
            continue
        matched = [p for p in pts if m.label in p.frame_time_of]
        if matched:
            base, basis = matched[0], "equal frame time"
        elif pts:
            base, basis = pts[0], comparison.budget.split(":")[0]
        else:
            continue
        entry = {"method": m.label, "baseline": base.label, "basis": basis,
                 "ms_per_frame": [m.metrics["ms_per_frame"], base.metrics["ms_per_frame"]],
                 "raw_frame": _ratio(base, m, "relmse_frame"),
                 "denoised_frame": _ratio(base, m, "relmse_denoised_frame"),
                 "accumulated": _ratio(base, m, "relmse_accumulated")}
        entry["text"] = (f"{m.label} against {base.label} ({basis}, {entry['ms_per_frame'][0]:.1f} vs "
                         f"{entry['ms_per_frame'][1]:.1f} ms per frame): per-frame relMSE raw "
                         f"{factor_text(entry['raw_frame'])}, denoised {factor_text(entry['denoised_frame'])}; "
                         f"accumulated {factor_text(entry['accumulated'])}")
        out.append(entry)
    return out
