"""The browser form of an animation: one self-contained HTML page (docs/visualisation.md §3).

The page embeds the drawing as JSON (per-frame arrays as base64 float32) and a small
hand-written WebGL 1 renderer (``viewer.js``, shipped in the package): no network, no
vendored library. It reports on itself for tests: ``window.__errors`` collects uncaught
errors, and once the first frame is drawn ``document.title`` reads ``pmd ok frame=K ...`` or
``pmd error: ...``. ``#paused`` or ``#frame=K`` after the file name starts paused.
"""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path

import numpy as np

from ._drawing import COLOURS, Drawing

_PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>pmd loading</title>
<style>
html,body{{margin:0;height:100%;overflow:hidden;background:#fff;font:13px sans-serif}}
canvas{{display:block;width:100vw;height:100vh;touch-action:none}}
#time{{position:fixed;left:10px;top:8px;font:15px monospace;pointer-events:none}}
#title{{position:fixed;left:10px;top:28px;color:#555;pointer-events:none}}
#status{{position:fixed;right:10px;top:8px;color:#b00;font-weight:bold}}
#legend{{position:fixed;right:10px;bottom:40px;color:#444;text-align:right;pointer-events:none}}
#bar{{position:fixed;left:0;right:0;bottom:0;display:flex;gap:8px;align-items:center;
padding:5px 10px;background:rgba(245,245,245,.85)}}
#slider{{flex:1}}
#layers label{{margin-left:6px;white-space:nowrap}}
</style></head><body>
<canvas id="c"></canvas>
<div id="time"></div><div id="title">{title}</div><div id="status"></div>
<div id="legend">{legend}</div>
<div id="bar"><button id="play">play</button><input id="slider" type="range" min="0" value="0">
<span id="frame"></span><span id="layers"></span><button id="reset">reset view</button></div>
<script>
window.__errors = [];
function __report(msg) {{
  window.__errors.push(String(msg));
  document.title = "pmd error: " + window.__errors.join("; ");
  var s = document.getElementById("status"); if (s) s.textContent = "error: " + msg;
}}
window.addEventListener("error", function (e) {{ __report(e.message || e); }});
window.addEventListener("unhandledrejection", function (e) {{ __report(e.reason); }});
</script>
<script id="pmd-data" type="application/json">{data}</script>
<script>
{viewer}
</script>
</body></html>
"""


def _b64(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype="<f4").tobytes()).decode("ascii")


def _legend(d: Drawing) -> str:
    hexc = {k: "#" + "".join(f"{int(round(255 * c)):02x}" for c in v)
            for k, v in COLOURS.items()}
    items = [f'<span style="color:{hexc["positive"]}">●</span> m &gt; 0']
    if np.any(d.sphere_mass < 0):
        items.append(f'<span style="color:{hexc["negative"]}">●</span> m &lt; 0')
    if np.any(d.sphere_mass == 0):
        items.append(f'<span style="color:{hexc["zero"]}">●</span> m = 0')
    items.append("radius ∝ |m|<sup>1/3</sup>")
    if d.visuals is not None and any(i.fallback for i in d.visuals["scene"].instances):
        items.append('<span style="color:#d99959">■</span> inertia box (mesh not drawn)')
    if d.cuts.shape[1]:
        items.append(f'<span style="color:{hexc["cut"]}">●</span> cut joints')
    if d.arrow is not None:
        items.append(f'<span style="color:{hexc["shaking"]}">➜</span> shaking force')
    if d.contact is not None:
        items.append(f'<span style="color:{hexc["contact"]}">➜</span> contact forces '
                     f'({1e3 * d.contact_scale:.3g} mm/N)')
    if d.planes:
        items.append('<span style="color:#8c99ad">■</span> contact plane'
                     + ("s" if len(d.planes) > 1 else ""))
    return " &nbsp; ".join(items) + "<br>drag: orbit · wheel: zoom · space: play/pause"


def _visual_data(d: Drawing) -> dict | None:
    """Meshes once each (vertices float32, faces uint16 or uint32, parts with colours),
    instances (body slot, mesh, pose 3×4 row-major, rgba or None) and the bodies' poses per
    frame (F, nbodies, 12)."""
    if d.visuals is None:
        return None
    scene = d.visuals["scene"]
    slot = {b: k for k, b in enumerate(d.visuals["bodies"])}
    meshes = []
    for m in scene.meshes:
        wide = len(m.vertices) > 65535
        idx = np.ascontiguousarray(m.faces, dtype="<u4" if wide else "<u2")
        meshes.append({
            "pos": _b64(m.vertices),
            "idx": base64.b64encode(idx.tobytes()).decode("ascii"),
            "wide": wide,
            "parts": [[int(a), int(n), None if c is None else [round(x, 4) for x in c]]
                      for a, n, c in m.parts] or [[0, len(m.faces), None]],
        })
    return {
        "meshes": meshes,
        "instances": [{"body": slot[i.body], "mesh": i.mesh,
                       "pose": np.round(i.pose.reshape(-1), 9).tolist(),
                       "rgba": None if i.rgba is None else [round(x, 4) for x in i.rgba]}
                      for i in scene.instances],
        "pose": _b64(d.visuals["pose"]),
        "nbodies": len(d.visuals["bodies"]),
    }


def page(d: Drawing, fps: float) -> str:
    """The HTML text of ``d`` played at ``fps``."""
    data = {
        "version": 1,
        "nframes": d.nframes,
        "fps": fps,
        "size": d.size,
        "times": _b64(d.times),
        "spheres": {
            "pos": _b64(d.spheres),
            "radius": [round(float(r), 6) for r in d.sphere_radius],
            "colour": np.round(d.sphere_colour, 4).tolist(),
        },
        "links": {"pos": _b64(d.links), "count": d.links.shape[1], "radius": d.link_radius},
        # Boxes are rigid: the link poses (12 floats) per frame, the corners once.
        "boxes": {"pose": _b64(d.box_pose), "corners": np.round(d.box_corners, 9).tolist()},
        "axes": {"pos": _b64(d.axes), "count": d.axes.shape[1], "radius": 0.45 * d.link_radius},
        "cuts": {"pos": _b64(d.cuts), "count": d.cuts.shape[1], "radius": 0.6 * d.link_radius},
        "trails": {
            "pos": _b64(d.trails),
            "colour": np.round(d.trail_colour, 4).tolist(),
            "radius": 0.015 * d.size,
        },
        "arrow": None if d.arrow is None else _b64(d.arrow),
        # Contact-force arrows (F, K, 2, 3): tail at the point; tail = head draws nothing.
        "contact": None if d.contact is None else {
            "pos": _b64(d.contact), "count": d.contact.shape[1], "radius": 0.7 * d.link_radius,
            "scale": d.contact_scale},
        # The ground: each contact plane (point, normal, its grid's square), drawn where it is,
        # translucent, with the grid on it; without planes, the grid under the motion.
        "grid": d.grid,
        "planes": [{k: p[k] for k in ("name", "point", "normal", "origin", "u", "v", "half",
                                      "step")} for p in d.planes],
        "camera": {**d.camera, "track": None if d.camera.get("track") is None
                   else _b64(np.asarray(d.camera["track"]))},
        "visuals": _visual_data(d),
        "show": list(d.show),
        "colours": {k: list(v) for k, v in COLOURS.items()},
    }
    # "</" cannot appear inside a <script> element.
    text = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    viewer = (Path(__file__).with_name("viewer.js")).read_text(encoding="utf-8")
    return _PAGE.format(title=html.escape(d.title), legend=_legend(d), data=text, viewer=viewer)


def write_html(d: Drawing, path: Path, *, fps: float, size: tuple[int, int]) -> None:
    """Writes the page (``size`` is the page's suggested size; it fills any window)."""
    del size  # the canvas follows the window
    Path(path).write_text(page(d, fps), encoding="utf-8")
