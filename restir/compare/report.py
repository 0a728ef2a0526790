"""The comparison as one folder of HTML that opens offline (no server, no network).

index.html holds the viewer and the tables; data.js the linear images (float16, base64) so that
the exposure and the false-colour error are computed in the page from radiance, not from a
tonemapped PNG; plotly.min.js (from the installed plotly package) draws the plots. Images are
also written as EXR beside it for other tools.
"""
import base64
import html
import json
import os

import numpy as np

from .structure import BLOCK_SIZES, TABLE_RADII


_VIEWER_JS = r"""
const D = RESTIR_DATA;
const W = D.width, H = D.height;
function halfToFloat(h) {
  const s = (h & 0x8000) ? -1 : 1, e = (h >> 10) & 0x1f, f = h & 0x3ff;
  if (e === 0) return s * Math.pow(2, -14) * (f / 1024);
  if (e === 31) return f ? NaN : s * Infinity;
  return s * Math.pow(2, e - 15) * (1 + f / 1024);
}
const HALF = new Float32Array(65536);
for (let i = 0; i < 65536; i++) HALF[i] = halfToFloat(i);
function decode(b64) {
  const bin = atob(b64), u16 = new Uint16Array(bin.length / 2), out = new Float32Array(bin.length / 2);
  for (let i = 0; i < u16.length; i++) u16[i] = bin.charCodeAt(2 * i) | (bin.charCodeAt(2 * i + 1) << 8);
  for (let i = 0; i < u16.length; i++) out[i] = HALF[u16[i]];
  return out;
}
const IMAGES = D.images.map(im => ({label: im.label, rgb: decode(im.data)}));
const REF = IMAGES[0].rgb;
// D.methods[i].views: the image index of each kind shown ('accumulated', 'frame', 'denoised');
// method 0 is the reference (one image for every kind)
const KINDS = {accumulated: 'accumulated', frame: 'last frame', denoised: 'last frame denoised'};
const view = {method: Math.min(1, D.methods.length - 1), kind: 'accumulated', index: 0, error: false, exposure: 0,
              scale: 1, x: 0, y: 0};
function imageOf(method, kind) {
  const v = D.methods[method].views;
  return v[kind] !== undefined && v[kind] !== null ? v[kind] : v.accumulated;
}
function srgb(v) { v = Math.max(0, Math.min(1, v)); return v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055; }
function ramp(t) {  // a perceptual dark-to-bright ramp (black, purple, orange, yellow) for the error view
  t = Math.max(0, Math.min(1, t));
  const c = [[0, 0, 4], [81, 18, 124], [183, 55, 121], [252, 137, 97], [252, 253, 191]];
  const x = t * (c.length - 1), i = Math.min(c.length - 2, Math.floor(x)), f = x - i;
  return c[i].map((a, k) => a + f * (c[i + 1][k] - a));
}
function bitmap(index, error) {
  const im = IMAGES[index].rgb, px = new ImageData(W, H), m = Math.pow(2, view.exposure);
  const errScale = parseFloat(document.getElementById('errmax').value);
  for (let p = 0; p < W * H; p++) {
    let r, g, b;
    if (error) {
      let e = 0;
      for (let c = 0; c < 3; c++) e += Math.abs(im[3 * p + c] - REF[3 * p + c]) / (Math.abs(REF[3 * p + c]) + 0.01);
      [r, g, b] = ramp(e / 3 / errScale);
    } else {
      r = 255 * srgb(im[3 * p] * m); g = 255 * srgb(im[3 * p + 1] * m); b = 255 * srgb(im[3 * p + 2] * m);
    }
    px.data[4 * p] = r; px.data[4 * p + 1] = g; px.data[4 * p + 2] = b; px.data[4 * p + 3] = 255;
  }
  return px;
}
const cache = {};
function source(index, error) {
  const key = index + ':' + error + ':' + view.exposure + ':' + document.getElementById('errmax').value;
  if (!cache[key]) {
    const c = document.createElement('canvas'); c.width = W; c.height = H;
    c.getContext('2d').putImageData(bitmap(index, error), 0, 0);
    cache[key] = c;
  }
  return cache[key];
}
function draw(canvas, index) {
  const ctx = canvas.getContext('2d');
  ctx.imageSmoothingEnabled = false;
  ctx.setTransform(1, 0, 0, 1, 0, 0);
  ctx.fillStyle = '#222'; ctx.fillRect(0, 0, canvas.width, canvas.height);
  const k = canvas.width / W;
  ctx.setTransform(view.scale * k, 0, 0, view.scale * k, -view.x * view.scale * k, -view.y * view.scale * k);
  ctx.drawImage(source(index, view.error && index !== 0), 0, 0);
}
function render() {
  view.index = imageOf(view.method, view.kind);
  draw(document.getElementById('main'), view.index);
  document.querySelectorAll('canvas.crop').forEach(c => draw(c, +c.dataset.index));
  document.querySelectorAll('.method').forEach(b => b.classList.toggle('active', +b.dataset.method === view.method));
  document.querySelectorAll('input[name=kind]').forEach(r => { r.checked = r.value === view.kind; });
  document.getElementById('shown').textContent = IMAGES[view.index].label + (view.error && view.index ? ' (relative error)' : '');
  document.getElementById('zoom').textContent = view.scale.toFixed(2) + 'x';
}
function show(i) { if (i >= 0 && i < D.methods.length) { view.method = i; render(); } }
function showKind(k) { if (k in KINDS && (k !== 'denoised' || D.denoised)) { view.kind = k; render(); } }
function zoomAt(factor, u, v) {  // u, v: image coordinates kept under the cursor
  const s = Math.max(1, Math.min(64, view.scale * factor));
  view.x = u - (u - view.x) * view.scale / s; view.y = v - (v - view.y) * view.scale / s; view.scale = s;
  clampView(); render();
}
function clampView() {
  const span = 1 / view.scale;
  view.x = Math.max(0, Math.min(W - W * span, view.x)); view.y = Math.max(0, Math.min(H - H * span, view.y));
}
window.restirView = view;  // read by the browser test
window.addEventListener('load', () => {
  const main = document.getElementById('main');
  main.addEventListener('wheel', e => {
    e.preventDefault();
    const r = main.getBoundingClientRect();
    zoomAt(e.deltaY < 0 ? 1.25 : 0.8, view.x + (e.clientX - r.left) / r.width * W / view.scale,
           view.y + (e.clientY - r.top) / r.height * H / view.scale);
  }, {passive: false});
  let drag = null;
  main.addEventListener('mousedown', e => { drag = [e.clientX, e.clientY]; });
  window.addEventListener('mouseup', () => { drag = null; });
  window.addEventListener('mousemove', e => {
    if (!drag) return;
    const r = main.getBoundingClientRect(), k = r.width / W * view.scale;
    view.x -= (e.clientX - drag[0]) / k; view.y -= (e.clientY - drag[1]) / k; drag = [e.clientX, e.clientY];
    clampView(); render();
  });
  document.querySelectorAll('.method').forEach(b => {
    b.addEventListener('mouseenter', () => show(+b.dataset.method));
    b.addEventListener('click', () => show(+b.dataset.method));
  });
  document.querySelectorAll('input[name=kind]').forEach(r => r.addEventListener('change', () => showKind(r.value)));
  document.getElementById('exposure').addEventListener('input', e => {
    view.exposure = parseFloat(e.target.value); document.getElementById('ev').textContent = view.exposure.toFixed(1); render();
  });
  document.getElementById('errmax').addEventListener('input', render);
  document.getElementById('errview').addEventListener('change', e => { view.error = e.target.checked; render(); });
  window.addEventListener('keydown', e => {
    if (e.key >= '0' && e.key <= '9') show(+e.key);
    else if (e.key === 'a') showKind('accumulated');
    else if (e.key === 'f') showKind('frame');
    else if (e.key === 'd') showKind(view.kind === 'denoised' ? 'frame' : 'denoised');
    else if (e.key === 'e') { view.error = !view.error; document.getElementById('errview').checked = view.error; render(); }
    else if (e.key === '+' || e.key === '=') zoomAt(1.25, view.x + W / view.scale / 2, view.y + H / view.scale / 2);
    else if (e.key === '-') zoomAt(0.8, view.x + W / view.scale / 2, view.y + H / view.scale / 2);
    else if (e.key === 'r') { view.scale = 1; view.x = view.y = 0; render(); }
  });
  render();
  document.body.dataset.ready = '1';
});
"""

_CSS = """
body { font-family: system-ui, sans-serif; margin: 16px; background: #fafafa; color: #222; }
h1 { font-size: 20px; } h2 { font-size: 16px; margin-top: 28px; }
#viewer { display: flex; gap: 16px; align-items: flex-start; }
#main { border: 1px solid #888; cursor: grab; image-rendering: pixelated; }
.method { display: block; width: 100%; text-align: left; margin: 2px 0; padding: 4px 8px; border: 1px solid #bbb; background: #fff; cursor: pointer; }
.method.active { background: #2a6; color: #fff; }
#crops { margin-top: 12px; } .crow { display: flex; gap: 8px; margin-bottom: 8px; }
#crops figure { margin: 0; font-size: 12px; } canvas.crop { border: 1px solid #aaa; image-rendering: pixelated; }
.headline { font-size: 14px; margin: 4px 0; }
table { border-collapse: collapse; font-size: 13px; } td, th { border: 1px solid #ccc; padding: 3px 8px; text-align: right; }
td:first-child, th:first-child { text-align: left; }
.note { color: #555; font-size: 13px; }
"""


def _encode(image) -> str:
    return base64.b64encode(np.ascontiguousarray(np.asarray(image, "<f2")).tobytes()).decode()


def _fmt(v, spec="{:.4g}"):
    return "-" if v is None else spec.format(v)


def _plots(result):
    """The report's plotly figures as HTML fragments (plotly.js is loaded once by the page)."""
    import plotly.graph_objects as go

    def fig_html(fig, div_id):
        fig.update_layout(height=380, margin=dict(l=60, r=20, t=40, b=50), template="plotly_white")
        return fig.to_html(include_plotlyjs=False, full_html=False, div_id=div_id)

    out = []
    for x_key, title, div in (("time", "accumulated relMSE against time", "plot-time"),
                              ("frames", "accumulated relMSE against frames", "plot-frames")):
        fig = go.Figure()
        for m in result.methods:
            x = m.frame_seconds if x_key == "time" else list(range(1, m.frames + 1))
            fig.add_trace(go.Scatter(x=x, y=m.accumulated_relmse, mode="lines", name=m.label))
        fig.update_xaxes(type="log", title="seconds" if x_key == "time" else "frames")
        fig.update_yaxes(type="log", title="relMSE")
        fig.update_layout(title=title)
        out.append(fig_html(fig, div))
    fig = go.Figure()
    for m in result.methods:
        fig.add_trace(go.Scatter(x=list(range(1, m.frames + 1)), y=m.frame_relmse, mode="lines", name=m.label))
    fig.update_xaxes(type="log", title="frame")
    fig.update_yaxes(type="log", title="relMSE of the frame")
    fig.update_layout(title="per-frame relMSE")
    out.append(fig_html(fig, "plot-per-frame"))
    radial = [m for m in result.methods if m.radial]
    if radial:
        fig = go.Figure()
        for m in radial:
            fig.add_trace(go.Scatter(x=m.radial["radii"], y=m.radial["values"], mode="lines+markers", name=m.label,
                                     error_y=dict(type="data", array=m.radial["standard_errors"], visible=True)))
        fig.update_xaxes(title="radius r (pixels, square ring)")
        fig.update_yaxes(title="correlation")
        first = radial[0].radial
        fig.update_layout(title=f"radial correlation of the error ({first['runs']} independent runs at frame "
                                f"{first['frame']}; bars: the standard error under independence)")
        out.append(fig_html(fig, "plot-radial"))
    stages = []
    for m in result.methods:
        stages += [s for s in m.stats.get("stages", {}) if s not in stages]
    fig = go.Figure()
    for s in stages:
        fig.add_trace(go.Bar(y=[m.label for m in result.methods], orientation="h", name=s,
                             x=[m.stats["stages"].get(s, {}).get("total_ms", 0.0) / max(m.frames, 1) for m in result.methods]))
    fig.update_layout(barmode="stack", title="ms per frame by stage")
    fig.update_xaxes(title="ms per frame")
    out.append(fig_html(fig, "plot-stages"))
    buffers = []
    for m in result.methods:
        buffers += [b for b in m.stats.get("bytes_per_pixel", {}) if b != "total" and b not in buffers]
    fig = go.Figure()
    for b in buffers:
        fig.add_trace(go.Bar(y=[m.label for m in result.methods], orientation="h", name=b,
                             x=[m.stats["bytes_per_pixel"].get(b, 0) for m in result.methods]))
    fig.update_layout(barmode="stack", title="memory: bytes per pixel by buffer", showlegend=len(buffers) <= 30)
    fig.update_xaxes(title="bytes per pixel")
    out.append(fig_html(fig, "plot-memory"))
    return out


def write_report(result, folder: str) -> str:
    """Write the report of `result` (a Comparison) into `folder`; returns the path of index.html."""
    import plotly.offline

    from ..image_io import write_exr

    os.makedirs(folder, exist_ok=True)
    images, methods = [("reference", result.reference.image)], [{"label": "reference", "views": {"accumulated": 0}}]
    for m in result.methods:
        views = {}
        for kind, img, label in (("accumulated", m.image, m.label), ("frame", m.last_frame, f"{m.label}: last frame"),
                                 ("denoised", m.denoised, f"{m.label}: last frame denoised")):
            if img is not None:
                views[kind] = len(images)
                images.append((label, img))
        methods.append({"label": m.label, "views": views})
    denoised = any(m.denoised is not None for m in result.methods)
    data = {"width": result.width, "height": result.height, "methods": methods, "denoised": denoised,
            "images": [{"label": label, "data": _encode(img)} for label, img in images]}
    with open(os.path.join(folder, "data.js"), "w") as f:
        f.write("const RESTIR_DATA = " + json.dumps(data) + ";\n")
    with open(os.path.join(folder, "plotly.min.js"), "w") as f:
        f.write(plotly.offline.get_plotlyjs())
    os.makedirs(os.path.join(folder, "images"), exist_ok=True)
    for i, (label, img) in enumerate(images):
        write_exr(os.path.join(folder, "images", f"{i}.exr"), np.asarray(img, np.float32))
    listing = [{"file": f"images/{index}.exr", "method": m["label"], "kind": kind, "label": images[index][0]}
               for m in methods for kind, index in m["views"].items()]
    with open(os.path.join(folder, "images.json"), "w") as f:  # which EXR is which
        json.dump(listing, f, indent=2)
    with open(os.path.join(folder, "comparison.json"), "w") as f:
        json.dump(result.to_dict(), f, indent=2, default=str)

    e = html.escape
    scale = 720 / max(result.width, result.height)
    main_w, main_h = round(result.width * scale), round(result.height * scale)
    crop = 200 / max(result.width, result.height)
    buttons = "".join(f'<button class="method" data-method="{i}">{i}: {e(m["label"])}</button>'
                      for i, m in enumerate(methods))
    kinds = "".join(f'<label><input type="radio" name="kind" value="{k}"{" disabled" if k == "denoised" and not denoised else ""}>'
                    f' {text} ({k[0]})</label><br>'
                    for k, text in (("accumulated", "accumulated"), ("frame", "last frame"),
                                    ("denoised", "last frame denoised")))

    def crop_fig(index, caption):
        return (f'<figure><canvas class="crop" data-index="{index}" width="{round(result.width * crop)}" '
                f'height="{round(result.height * crop)}"></canvas><figcaption>{e(caption)}</figcaption></figure>')

    crops = [f'<div class="crow">{crop_fig(0, "0: reference")}</div>']
    for i, m in enumerate(methods[1:], start=1):  # side by side: accumulated, the last frame raw and denoised
        crops.append('<div class="crow">' + "".join(crop_fig(idx, f"{i}: {images[idx][0]}")
                                                    for idx in m["views"].values()) + "</div>")
    rows, shape_rows = [], []
    for m in result.methods:
        x = m.metrics
        z = f" (z {x['mean_z']:+.2f}, MDB {100 * x['mean_mdb']:.2f}%)" if x["mean_z"] is not None else ""
        mem = m.stats.get("bytes_per_pixel", {}).get("total")
        rows.append(f"<tr><td>{e(m.label)}</td><td>{m.frames}</td><td>{m.spp}</td><td>{x['ms_per_frame']:.1f}</td>"
                    f"<td>{x['relmse_frame']:.4g}</td><td>{x['relmse_accumulated']:.4g}</td><td>{x['mape']:.4g}</td>"
                    f"<td>{_fmt(x['flip'], '{:.4f}')}</td><td>{x['mean_ratio']:.4f}{z}</td>"
                    f"<td>{_fmt(x.get('relmse_denoised_frame'))}</td><td>{_fmt(x.get('flip_denoised_frame'), '{:.4f}')}</td>"
                    f"<td>{_fmt(mem, '{:.0f}')}</td></tr>")
        radial = dict(zip(m.radial["radii"], m.radial["values"])) if m.radial else {}
        shape_rows.append(f"<tr><td>{e(m.label)}</td>"
                          + "".join(f"<td>{_fmt(x['correlation_factor'][str(b)], '{:.2f}')}</td>" for b in BLOCK_SIZES)
                          + "".join(f"<td>{_fmt(radial.get(r), '{:.3f}')}</td>" for r in TABLE_RADII)
                          + f"<td>{_fmt(x['temporal_correlation'], '{:.3f}')}</td></tr>")
    headline = "".join(f'<p class="headline">{e(h["text"])}</p>' for h in result.headline)
    notes = "".join(f'<p class="note">note: {e(n)}</p>' for n in result.notes)
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>restir compare: {e(result.scene)}</title>
<style>{_CSS}</style>
<script src="plotly.min.js"></script><script src="data.js"></script><script>{_VIEWER_JS}</script></head>
<body>
<h1>{e(result.scene)}: {result.width}x{result.height}, {e(result.budget)}</h1>
<p class="note">Reference: {e(result.reference.source)}. Per-frame relMSE: mean over the frames after the first
{result.warmup} (warm-up); accumulated: the average of every frame within the budget. relMSE = (x - y)^2 / (y^2 + 0.01),
MAPE = |x - y| / (|y| + 0.01), FLIP: HDR-FLIP. Mean ratio: image mean over the reference's, with the z of
restir's image-level bias test (batch means of consecutive frames) and its minimum detectable bias.</p>
{notes}
<div id="viewer">
<canvas id="main" width="{main_w}" height="{main_h}"></canvas>
<div style="min-width: 260px">
<p><b id="shown"></b> &middot; zoom <span id="zoom"></span></p>
{buttons}
<p>exposure <input id="exposure" type="range" min="-8" max="8" step="0.5" value="0"> <span id="ev">0.0</span> EV</p>
<p>{kinds}</p>
<p><label><input id="errview" type="checkbox"> relative error (key e)</label>,
full scale <input id="errmax" type="number" min="0.01" step="0.05" value="0.5" style="width: 5em"></p>
<p class="note">Keys 0-9 show a method (0: reference), hover or click a name; a, f, d: its accumulated image,
last frame, last frame denoised (d toggles raw and denoised); wheel or +/- zooms, drag pans, r resets. The crops
below follow the view and the error view.</p>
</div></div>
<div id="crops">{''.join(crops)}</div>
<h2>Against the path tracer</h2>
{headline or '<p class="note">no path tracer among the methods</p>'}
<p class="note">Factor: the path tracer's relMSE over the method's (above 1: the method's error is lower). At
equal time the path tracer is rendered at each method's frame time (its frame time fitted as a + b spp), so
per frame both had the same time.</p>
<h2>Metrics</h2>
<table><tr><th>method</th><th>frames</th><th>spp/frame</th><th>ms/frame</th><th>relMSE per frame</th>
<th>relMSE accumulated</th><th>MAPE</th><th>FLIP</th><th>mean ratio</th><th>denoised relMSE per frame</th>
<th>denoised FLIP per frame</th><th>bytes/pixel</th></tr>
{''.join(rows)}</table>
<h2>Error structure: what a denoiser sees</h2>
<p class="note">Relative error e = (x - y) / sqrt(y^2 + 0.01) of single frames after the warm-up. Correlation
factor at block size B: B^2 mean(block mean(e)^2) / mean(e^2) over aligned B x B blocks; 1 for independent
pixel errors, B^2 for errors constant over each block (a B x B average leaves factor / B^2 of the error).
Radial correlation: independent runs at one frame index, each pixel standardised over the runs, Pearson
correlation with the pixel at offset (dy, dx), averaged over the square ring of radius r. Temporal: the
correlation of consecutive frames' errors.</p>
<table><tr><th>method</th>{''.join(f"<th>factor B={b}</th>" for b in BLOCK_SIZES)}
{''.join(f"<th>radial r={r}</th>" for r in TABLE_RADII)}<th>temporal</th></tr>
{''.join(shape_rows)}</table>
<h2>Convergence</h2>
{''.join(_plots(result))}
</body></html>
"""
    index = os.path.join(folder, "index.html")
    with open(index, "w") as f:
        f.write(page)
    return index
