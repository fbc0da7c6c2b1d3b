// pointmass_dyn viewer: a small WebGL 1 renderer for one Drawing (docs/visualisation.md).
// Reads the JSON in <script id="pmd-data">; draws spheres, cylinders, cones and lines with
// one shader; orbit (drag), zoom (wheel), play/pause, scrub. The camera matrix is the one
// pointmass_dyn.animation.view_projection computes, so a test can project world points.
(function () {
  "use strict";
  const D = JSON.parse(document.getElementById("pmd-data").textContent);
  const $ = (id) => document.getElementById(id);
  function f32(b64) {
    const s = atob(b64);
    const u = new Uint8Array(s.length);
    for (let i = 0; i < s.length; i++) u[i] = s.charCodeAt(i);
    return new Float32Array(u.buffer);
  }
  const F = D.nframes;
  const T = f32(D.times);
  const SP = f32(D.spheres.pos), NS = D.spheres.radius.length;
  const LK = f32(D.links.pos), NL = D.links.count;
  const AX = f32(D.axes.pos), NA = D.axes.count;
  const BP = f32(D.boxes.pose), NB = D.boxes.corners.length;
  const CU = f32(D.cuts.pos), NC = D.cuts.count;
  const TR = f32(D.trails.pos), NT = D.trails.colour.length;
  const AR = D.arrow ? f32(D.arrow) : null;
  // A page whose data do not fit together fails loudly, not with a blank canvas.
  const check = (ok, what) => { if (!ok) throw new Error("pmd-data: " + what); };
  check(Number.isInteger(F) && F >= 1, "nframes must be an integer >= 1");
  check(T.length === F, "times: " + T.length + " values for " + F + " frames");
  check(SP.length === 3 * F * NS, "spheres.pos: wrong length");
  check(LK.length === 6 * F * NL && AX.length === 6 * F * NA && CU.length === 6 * F * NC,
    "segments: wrong length");
  check(BP.length === 12 * F * NB, "boxes: wrong length");
  check(TR.length === 3 * F * NT && (!AR || AR.length === 6 * F), "trails/arrow: wrong length");

  const canvas = $("c");
  const gl = canvas.getContext("webgl", { antialias: true, preserveDrawingBuffer: true });
  if (!gl) throw new Error("WebGL is not available in this browser");

  // ---- shader: lit (headlight diffuse + ambient) or flat colour
  const VS = "attribute vec3 aP;attribute vec3 aN;uniform mat4 uVP;uniform mat4 uM;" +
    "varying vec3 vN;void main(){vN=mat3(uM)*aN;gl_Position=uVP*uM*vec4(aP,1.0);}";
  const FS = "precision mediump float;varying vec3 vN;uniform vec3 uC;uniform float uLit;" +
    "uniform vec3 uL;void main(){float d=abs(dot(normalize(vN+1e-9),uL));" +
    "gl_FragColor=vec4(uLit>0.5?uC*(0.35+0.65*d):uC,1.0);}";
  function shader(type, src) {
    const s = gl.createShader(type);
    gl.shaderSource(s, src);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  }
  const prog = gl.createProgram();
  gl.attachShader(prog, shader(gl.VERTEX_SHADER, VS));
  gl.attachShader(prog, shader(gl.FRAGMENT_SHADER, FS));
  gl.linkProgram(prog);
  if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(prog));
  gl.useProgram(prog);
  const aP = gl.getAttribLocation(prog, "aP"), aN = gl.getAttribLocation(prog, "aN");
  const U = {};
  for (const n of ["uVP", "uM", "uC", "uLit", "uL"]) U[n] = gl.getUniformLocation(prog, n);

  // ---- meshes: interleaved position + normal, drawn as triangles
  function mesh(verts) {
    const b = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, b);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(verts), gl.STATIC_DRAW);
    return { buf: b, n: verts.length / 6 };
  }
  function sphereMesh(nu, nv) {
    const v = [];
    const p = (i, j) => {
      const th = (Math.PI * j) / nv, ph = (2 * Math.PI * i) / nu;
      const x = Math.sin(th) * Math.cos(ph), y = Math.sin(th) * Math.sin(ph), z = Math.cos(th);
      return [x, y, z, x, y, z];
    };
    for (let j = 0; j < nv; j++)
      for (let i = 0; i < nu; i++)
        v.push(...p(i, j), ...p(i + 1, j), ...p(i + 1, j + 1), ...p(i, j), ...p(i + 1, j + 1), ...p(i, j + 1));
    return mesh(v);
  }
  // Unit cylinder (radius 1, z from 0 to 1) or cone (apex at z = 1), sides only.
  function tubeMesh(n, cone) {
    const v = [];
    for (let i = 0; i < n; i++) {
      const a0 = (2 * Math.PI * i) / n, a1 = (2 * Math.PI * (i + 1)) / n;
      const c0 = Math.cos(a0), s0 = Math.sin(a0), c1 = Math.cos(a1), s1 = Math.sin(a1);
      const top = cone ? 0 : 1, nz = cone ? 1 : 0;
      v.push(c0, s0, 0, c0, s0, nz, c1, s1, 0, c1, s1, nz, top * c1, top * s1, 1, c1, s1, nz);
      v.push(c0, s0, 0, c0, s0, nz, top * c1, top * s1, 1, c1, s1, nz, top * c0, top * s0, 1, c0, s0, nz);
      if (cone) {  // base disc
        v.push(0, 0, 0, 0, 0, -1, c1, s1, 0, 0, 0, -1, c0, s0, 0, 0, 0, -1);
      }
    }
    return mesh(v);
  }
  const SPHERE = sphereMesh(20, 12), CYL = tubeMesh(14, false), CONE = tubeMesh(18, true);
  const lineBuf = gl.createBuffer();

  function bindMesh(m) {
    gl.bindBuffer(gl.ARRAY_BUFFER, m.buf);
    gl.enableVertexAttribArray(aN);
    gl.vertexAttribPointer(aP, 3, gl.FLOAT, false, 24, 0);
    gl.vertexAttribPointer(aN, 3, gl.FLOAT, false, 24, 12);
    gl.enableVertexAttribArray(aP);
  }
  const M = new Float32Array(16);
  function drawMesh(m, mat, colour, lit) {
    gl.uniformMatrix4fv(U.uM, false, mat);
    gl.uniform3fv(U.uC, colour);
    gl.uniform1f(U.uLit, lit ? 1 : 0);
    gl.drawArrays(gl.TRIANGLES, 0, m.n);
  }
  function sphereMatrix(x, y, z, r) {
    M.fill(0);
    M[0] = M[5] = M[10] = r;
    M[12] = x; M[13] = y; M[14] = z; M[15] = 1;
    return M;
  }
  // Columns: r·e1, r·e2, (b − a), a, with e1, e2 ⟂ b − a.
  function tubeMatrix(a, b, r) {
    const zx = b[0] - a[0], zy = b[1] - a[1], zz = b[2] - a[2];
    const L = Math.hypot(zx, zy, zz);
    if (L < 1e-12) return null;
    const ux = zx / L, uy = zy / L, uz = zz / L;
    const h = Math.abs(ux) < 0.9 ? [1, 0, 0] : [0, 1, 0];
    let xx = h[1] * uz - h[2] * uy, xy = h[2] * ux - h[0] * uz, xz = h[0] * uy - h[1] * ux;
    const xl = Math.hypot(xx, xy, xz);
    xx /= xl; xy /= xl; xz /= xl;
    const yx = uy * xz - uz * xy, yy = uz * xx - ux * xz, yz = ux * xy - uy * xx;
    M.set([r * xx, r * xy, r * xz, 0, r * yx, r * yy, r * yz, 0, zx, zy, zz, 0, a[0], a[1], a[2], 1]);
    return M;
  }
  const IDENT = new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
  function drawLines(pts, colour, mode) {
    gl.bindBuffer(gl.ARRAY_BUFFER, lineBuf);
    gl.bufferData(gl.ARRAY_BUFFER, pts, gl.DYNAMIC_DRAW);
    gl.disableVertexAttribArray(aN);
    gl.vertexAttrib3f(aN, 0, 0, 1);
    gl.enableVertexAttribArray(aP);
    gl.vertexAttribPointer(aP, 3, gl.FLOAT, false, 12, 0);
    gl.uniformMatrix4fv(U.uM, false, IDENT);
    gl.uniform3fv(U.uC, colour);
    gl.uniform1f(U.uLit, 0);
    gl.drawArrays(mode, 0, pts.length / 3);
  }

  // ---- static lines: ground grid and world frame
  const G = D.grid, gv = [];
  for (let k = -G.half; k <= G.half + 1e-9 * G.half; k += G.step) {
    gv.push(G.center[0] + k, G.center[1] - G.half, G.z, G.center[0] + k, G.center[1] + G.half, G.z);
    gv.push(G.center[0] - G.half, G.center[1] + k, G.z, G.center[0] + G.half, G.center[1] + k, G.z);
  }
  const GRID = new Float32Array(gv);
  const W = 0.15 * D.size;
  const FRAME = [
    [new Float32Array([0, 0, 0, W, 0, 0]), [0.85, 0.1, 0.1]],
    [new Float32Array([0, 0, 0, 0, W, 0]), [0.1, 0.6, 0.1]],
    [new Float32Array([0, 0, 0, 0, 0, W]), [0.1, 0.2, 0.85]],
  ];
  // Trails as one contiguous strip each.
  const TRAILS = [];
  for (let j = 0; j < NT; j++) {
    const a = new Float32Array(3 * F);
    for (let f = 0; f < F; f++) for (let c = 0; c < 3; c++) a[3 * f + c] = TR[(f * NT + j) * 3 + c];
    TRAILS.push(a);
  }

  // ---- camera: the same matrix as animation.view_projection (column-major here)
  const cam0 = D.camera;
  const cam = { az: cam0.azimuth, el: cam0.elevation, d: cam0.distance, t: cam0.target.slice() };
  function viewProj(aspect) {
    const az = (cam.az * Math.PI) / 180, el = (cam.el * Math.PI) / 180, d = cam.d;
    const e = [cam.t[0] + d * Math.cos(el) * Math.cos(az), cam.t[1] + d * Math.cos(el) * Math.sin(az),
      cam.t[2] + d * Math.sin(el)];
    const f = [cam.t[0] - e[0], cam.t[1] - e[1], cam.t[2] - e[2]];
    const fl = Math.hypot(...f);
    f[0] /= fl; f[1] /= fl; f[2] /= fl;
    const s = [f[1], -f[0], 0];  // f × z
    const sl = Math.hypot(...s);
    s[0] /= sl; s[1] /= sl;
    const u = [s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]];
    const V = [s, u, [-f[0], -f[1], -f[2]]];  // rows of the view rotation
    const tv = V.map((r) => -(r[0] * e[0] + r[1] * e[1] + r[2] * e[2]));
    const n = cam0.distance / 100, fa = cam0.distance * 100 * Math.max(1, d / cam0.distance);
    const ft = 1 / Math.tan(((cam0.fov * Math.PI) / 180) / 2);
    const P = [ft / aspect, ft, (fa + n) / (n - fa), (2 * fa * n) / (n - fa)];
    // clip = P · V; row i of the product, stored column-major.
    const out = new Float32Array(16);
    for (let c = 0; c < 3; c++) {
      out[4 * c + 0] = P[0] * V[0][c];
      out[4 * c + 1] = P[1] * V[1][c];
      out[4 * c + 2] = P[2] * V[2][c];
      out[4 * c + 3] = -V[2][c];
    }
    out[12] = P[0] * tv[0];
    out[13] = P[1] * tv[1];
    out[14] = P[2] * tv[2] + P[3];
    out[15] = -tv[2];
    gl.uniform3f(U.uL, -f[0], -f[1], -f[2]);
    return out;
  }

  // Each link's point-mass box: corner c has bit k set where it takes the high value on
  // axis k; its 12 edges join corners differing in one bit.
  const EDGES = [];
  for (const bit of [1, 2, 4]) for (let a = 0; a < 8; a++) if (!(a & bit)) EDGES.push([a, a | bit]);
  const BOXES = new Float32Array(NB * 12 * 6);
  function boxEdges() {
    const w = new Float32Array(24);
    for (let i = 0; i < NB; i++) {
      const o = (frame * NB + i) * 12, [lo, hi] = D.boxes.corners[i];
      for (let c = 0; c < 8; c++) {
        const x = [(c & 1 ? hi : lo)[0], (c & 2 ? hi : lo)[1], (c & 4 ? hi : lo)[2]];
        for (let r = 0; r < 3; r++)
          w[3 * c + r] = BP[o + 9 + r] + BP[o + 3 * r] * x[0] + BP[o + 3 * r + 1] * x[1] + BP[o + 3 * r + 2] * x[2];
      }
      EDGES.forEach(([a, b], e) => {
        BOXES.set(w.subarray(3 * a, 3 * a + 3), (i * 12 + e) * 6);
        BOXES.set(w.subarray(3 * b, 3 * b + 3), (i * 12 + e) * 6 + 3);
      });
    }
    return BOXES;
  }

  // ---- drawing one frame
  let frame = 0;
  const c3 = (arr, i) => [arr[i], arr[i + 1], arr[i + 2]];
  function draw() {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    gl.viewport(0, 0, w, h);
    gl.clearColor(1, 1, 1, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.uniformMatrix4fv(U.uVP, false, viewProj(w / h));
    drawLines(GRID, D.colours.grid, gl.LINES);
    for (const [pts, col] of FRAME) drawLines(pts, col, gl.LINES);
    for (let j = 0; j < NT; j++)
      if (frame > 0) drawLines(TRAILS[j].subarray(0, 3 * (frame + 1)), D.trails.colour[j], gl.LINE_STRIP);
    if (NB) drawLines(boxEdges(), D.colours.box, gl.LINES);
    bindMesh(CYL);
    for (let i = 0; i < NL; i++) {
      const o = (frame * NL + i) * 6;
      const m = tubeMatrix(c3(LK, o), c3(LK, o + 3), D.links.radius);
      if (m) drawMesh(CYL, m, D.colours.link, true);
    }
    for (let i = 0; i < NA; i++) {
      const o = (frame * NA + i) * 6;
      const m = tubeMatrix(c3(AX, o), c3(AX, o + 3), D.axes.radius);
      if (m) drawMesh(CYL, m, D.colours.axis, true);
    }
    for (let i = 0; i < NC; i++) {
      const o = (frame * NC + i) * 6;
      const m = tubeMatrix(c3(CU, o), c3(CU, o + 3), D.cuts.radius);
      if (m) drawMesh(CYL, m, D.colours.cut, true);
    }
    let shaft = null;
    if (AR) {
      const a = c3(AR, frame * 6), b = c3(AR, frame * 6 + 3);
      const k = [0, 1, 2].map((c) => a[c] + 0.8 * (b[c] - a[c]));
      shaft = [k, b];
      const m = tubeMatrix(a, k, D.links.radius * 1.2);
      if (m) drawMesh(CYL, m, D.colours.shaking, true);
    }
    bindMesh(SPHERE);
    for (let i = 0; i < NS; i++) {
      const o = (frame * NS + i) * 3;
      drawMesh(SPHERE, sphereMatrix(SP[o], SP[o + 1], SP[o + 2], D.spheres.radius[i]),
        D.spheres.colour[i], true);
    }
    for (let i = 0; i < NC; i++) {
      const o = (frame * NC + i) * 6;
      drawMesh(SPHERE, sphereMatrix(CU[o], CU[o + 1], CU[o + 2], D.cuts.radius * 2.2), D.colours.cut, true);
    }
    if (shaft) {
      bindMesh(CONE);
      const m = tubeMatrix(shaft[0], shaft[1], D.links.radius * 3);
      if (m) drawMesh(CONE, m, D.colours.shaking, true);
    }
    // Trail heads last, over everything, in flat colour: a tracked point stays visible (and
    // is a disc of exactly that colour on screen).
    gl.disable(gl.DEPTH_TEST);
    bindMesh(SPHERE);
    for (let j = 0; j < NT; j++) {
      const o = (frame * NT + j) * 3;
      drawMesh(SPHERE, sphereMatrix(TR[o], TR[o + 1], TR[o + 2], D.trails.radius), D.trails.colour[j], false);
    }
    $("time").textContent = "t = " + T[frame].toFixed(3) + " s";
    $("frame").textContent = frame + 1 + " / " + F;
    $("slider").value = String(frame);
  }

  // ---- controls
  const hash = new URLSearchParams(location.hash.slice(1));
  let playing = !hash.has("paused") && !hash.has("frame") && F > 1;
  if (hash.has("frame")) frame = Math.min(F - 1, Math.max(0, parseInt(hash.get("frame"), 10) || 0));
  let start = performance.now() - (frame / D.fps) * 1000;
  const slider = $("slider");
  slider.max = String(F - 1);
  const playBtn = $("play");
  function setPlaying(p) {
    playing = p && F > 1;
    playBtn.textContent = playing ? "pause" : "play";
    start = performance.now() - (frame / D.fps) * 1000;
    if (playing) requestAnimationFrame(tick);
  }
  playBtn.onclick = () => setPlaying(!playing);
  slider.oninput = () => { frame = parseInt(slider.value, 10); setPlaying(false); draw(); };
  $("reset").onclick = () => {
    Object.assign(cam, { az: cam0.azimuth, el: cam0.elevation, d: cam0.distance, t: cam0.target.slice() });
    draw();
  };
  let drag = null;
  canvas.addEventListener("pointerdown", (e) => { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
  canvas.addEventListener("pointerup", () => { drag = null; });
  canvas.addEventListener("pointermove", (e) => {
    if (!drag) return;
    cam.az -= (e.clientX - drag[0]) * 0.4;
    cam.el = Math.max(-89, Math.min(89, cam.el + (e.clientY - drag[1]) * 0.4));
    drag = [e.clientX, e.clientY];
    if (!playing) draw();
  });
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    cam.d *= Math.exp(e.deltaY * 0.001);
    if (!playing) draw();
  }, { passive: false });
  document.addEventListener("keydown", (e) => { if (e.key === " ") { e.preventDefault(); setPlaying(!playing); } });
  window.addEventListener("resize", () => { if (!playing) draw(); });
  function tick(now) {
    if (!playing) return;
    // rAF's timestamp may precede the performance.now() that set `start`: clamp at 0.
    frame = Math.floor(Math.max(0, (now - start) / 1000) * D.fps) % F;
    draw();
    requestAnimationFrame(tick);
  }

  // The first frame now (not on the next animation frame), then report.
  draw();
  gl.finish();
  const err = gl.getError();
  if (err !== gl.NO_ERROR) throw new Error("WebGL error " + err);
  window.__firstFrame = frame;
  // For tests and the console: the frame shown and the box edges the page draws for it.
  window.__pmd = { frame: () => frame, boxEdges: () => Array.from(boxEdges()) };
  window.__status = "ok";
  $("status").textContent = window.__errors.length ? "error: " + window.__errors.join("; ") : "";
  document.title = (window.__errors.length ? "pmd error: " + window.__errors.join("; ") : "pmd ok") +
    " frame=" + frame + " size=" + canvas.width + "x" + canvas.height;
  setPlaying(playing);
})();
