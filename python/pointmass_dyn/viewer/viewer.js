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
  const CF = D.contact ? f32(D.contact.pos) : null, NK = D.contact ? D.contact.count : 0;
  const VIS = D.visuals;
  const VP = VIS ? f32(VIS.pose) : null, NV = VIS ? VIS.nbodies : 0;
  const TRACK = D.camera.track ? f32(D.camera.track) : null;
  // A page whose data do not fit together fails loudly, not with a blank canvas.
  const check = (ok, what) => { if (!ok) throw new Error("pmd-data: " + what); };
  check(Number.isInteger(F) && F >= 1, "nframes must be an integer >= 1");
  check(T.length === F, "times: " + T.length + " values for " + F + " frames");
  check(SP.length === 3 * F * NS, "spheres.pos: wrong length");
  check(LK.length === 6 * F * NL && AX.length === 6 * F * NA && CU.length === 6 * F * NC,
    "segments: wrong length");
  check(BP.length === 12 * F * NB, "boxes: wrong length");
  check(TR.length === 3 * F * NT && (!AR || AR.length === 6 * F), "trails/arrow: wrong length");
  check(!CF || (Number.isInteger(NK) && CF.length === 6 * F * NK), "contact: wrong length");
  check(!VIS || VP.length === 12 * F * NV, "visuals.pose: wrong length");
  check(!TRACK || TRACK.length === 3 * F, "camera.track: wrong length");
  // Layers shown (toggles in the bar; `#show=robot,masses` in the address overrides).
  const LAYERS = { robot: "robot", masses: "point masses", links: "links", axes: "joint axes",
    frames: "frames", forces: "forces" };
  const shown = new Set(D.show);

  const canvas = $("c");
  const gl = canvas.getContext("webgl", { antialias: true, preserveDrawingBuffer: true });
  if (!gl) throw new Error("WebGL is not available in this browser");

  // ---- shader: lit (headlight diffuse + ambient, at most 90 % of the colour, so a white
  // surface stays apart from the white background) or flat colour
  const VS = "attribute vec3 aP;attribute vec3 aN;uniform mat4 uVP;uniform mat4 uM;" +
    "varying vec3 vN;void main(){vN=mat3(uM)*aN;gl_Position=uVP*uM*vec4(aP,1.0);}";
  const FS = "precision mediump float;varying vec3 vN;uniform vec3 uC;uniform float uLit;" +
    "uniform vec3 uL;uniform float uA;void main(){float d=abs(dot(normalize(vN+1e-9),uL));" +
    "gl_FragColor=vec4(uLit>0.5?uC*(0.3+0.6*d):uC,uA);}";
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
  for (const n of ["uVP", "uM", "uC", "uLit", "uL", "uA"]) U[n] = gl.getUniformLocation(prog, n);

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

  // ---- the robot's meshes: flat arrays expanded per corner, each corner's normal the
  // average of the faces around its vertex that bend less than ~37° from its own face
  // (smooth on curved surfaces, sharp at creases).
  function robotMesh(m) {
    const P = f32(m.pos);
    const raw = atob(m.idx), bytes = new Uint8Array(raw.length);
    for (let i = 0; i < raw.length; i++) bytes[i] = raw.charCodeAt(i);
    const I = m.wide ? new Uint32Array(bytes.buffer) : new Uint16Array(bytes.buffer);
    const nf = I.length / 3, nv = P.length / 3;
    for (let i = 0; i < I.length; i++) check(I[i] < nv, "visuals: face index out of range");
    const FN = new Float32Array(3 * nf);
    for (let f = 0; f < nf; f++) {
      const a = 3 * I[3 * f], b = 3 * I[3 * f + 1], c = 3 * I[3 * f + 2];
      const ux = P[b] - P[a], uy = P[b + 1] - P[a + 1], uz = P[b + 2] - P[a + 2];
      const vx = P[c] - P[a], vy = P[c + 1] - P[a + 1], vz = P[c + 2] - P[a + 2];
      FN[3 * f] = uy * vz - uz * vy; FN[3 * f + 1] = uz * vx - ux * vz; FN[3 * f + 2] = ux * vy - uy * vx;
    }
    const start = new Uint32Array(nv + 1);
    for (let i = 0; i < I.length; i++) start[I[i] + 1]++;
    for (let v = 0; v < nv; v++) start[v + 1] += start[v];
    const fill = start.slice(0, nv), around = new Uint32Array(I.length);
    for (let i = 0; i < I.length; i++) around[fill[I[i]]++] = (i / 3) | 0;
    const out = new Float32Array(nf * 18);
    for (let f = 0; f < nf; f++) {
      const fl = Math.hypot(FN[3 * f], FN[3 * f + 1], FN[3 * f + 2]) || 1;
      for (let c = 0; c < 3; c++) {
        const v = I[3 * f + c];
        let nx = 0, ny = 0, nz = 0;
        for (let k = start[v]; k < start[v + 1]; k++) {
          const g = around[k];
          const gl2 = Math.hypot(FN[3 * g], FN[3 * g + 1], FN[3 * g + 2]) || 1;
          const cos = (FN[3 * f] * FN[3 * g] + FN[3 * f + 1] * FN[3 * g + 1] + FN[3 * f + 2] * FN[3 * g + 2]) / (fl * gl2);
          if (cos > 0.8) { nx += FN[3 * g]; ny += FN[3 * g + 1]; nz += FN[3 * g + 2]; }
        }
        const o = (3 * f + c) * 6;
        out[o] = P[3 * v]; out[o + 1] = P[3 * v + 1]; out[o + 2] = P[3 * v + 2];
        out[o + 3] = nx; out[o + 4] = ny; out[o + 5] = nz;
      }
    }
    const b = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, b);
    gl.bufferData(gl.ARRAY_BUFFER, out, gl.STATIC_DRAW);
    for (const [a, n] of m.parts) check(a + n <= nf, "visuals: parts exceed the faces");
    return { buf: b, n: 3 * nf, parts: m.parts };
  }
  const ROBOT = VIS ? VIS.meshes.map(robotMesh) : [];
  if (VIS) for (const inst of VIS.instances)
    check(inst.mesh < ROBOT.length && inst.body < NV && inst.pose.length === 12, "visuals: bad instance");
  const DEFAULT_RGB = [0.72, 0.74, 0.78];
  // body pose (row-major R | t, 12 floats) ∘ instance pose, as a column-major 4×4.
  function instanceMatrix(o, p) {
    const out = new Float32Array(16);
    for (let r = 0; r < 3; r++) {
      for (let c = 0; c < 3; c++)
        out[4 * c + r] = VP[o + 3 * r] * p[4 * 0 + c] + VP[o + 3 * r + 1] * p[4 * 1 + c] + VP[o + 3 * r + 2] * p[4 * 2 + c];
      out[12 + r] = VP[o + 9 + r] + VP[o + 3 * r] * p[3] + VP[o + 3 * r + 1] * p[7] + VP[o + 3 * r + 2] * p[11];
    }
    out[15] = 1;
    return out;
  }
  function drawRobot() {
    for (const inst of VIS.instances) {
      const m = ROBOT[inst.mesh];
      bindMesh(m);
      gl.uniformMatrix4fv(U.uM, false, instanceMatrix((frame * NV + inst.body) * 12, inst.pose));
      gl.uniform1f(U.uLit, 1);
      for (const [a, n, rgb] of m.parts) {
        gl.uniform3fv(U.uC, inst.rgba ? inst.rgba.slice(0, 3) : rgb || DEFAULT_RGB);
        gl.drawArrays(gl.TRIANGLES, 3 * a, 3 * n);
      }
    }
  }

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
  // The ground: each contact plane where it is (a translucent square, axes u, v, with the grid
  // on it); without contact planes, a grid at right angles to gravity under the motion.
  const PLANES = D.planes || [];
  for (const P of PLANES)
    check(P.origin.length === 3 && P.u.length === 3 && P.v.length === 3 && P.half > 0 && P.step > 0,
      "planes: bad plane");
  const gv = [], fill = [];
  for (const G of PLANES.length ? PLANES : [D.grid]) {
    const gp = (a, b) => [0, 1, 2].map((c) => G.origin[c] + a * G.u[c] + b * G.v[c]);
    for (let k = -G.half; k <= G.half + 1e-9 * G.half; k += G.step) {
      gv.push(...gp(k, -G.half), ...gp(k, G.half), ...gp(-G.half, k), ...gp(G.half, k));
    }
    if (G !== D.grid) {
      const h = G.half;
      fill.push(...gp(-h, -h), ...gp(h, -h), ...gp(h, h), ...gp(-h, -h), ...gp(h, h), ...gp(-h, h));
    }
  }
  const GRID = new Float32Array(gv), PLANE_FILL = new Float32Array(fill);
  const PLANE_RGB = [0.55, 0.6, 0.68];
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
  // (e1, e2, up): up is −gravity; e1 is world x made orthogonal to it (y if up is along x).
  const UP = (cam0.up || [0, 0, 1]).slice();
  const upl = Math.hypot(...UP);
  for (let c = 0; c < 3; c++) UP[c] /= upl;
  const ref = Math.abs(UP[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0];
  const rd = ref[0] * UP[0] + ref[1] * UP[1] + ref[2] * UP[2];
  const E1 = [0, 1, 2].map((c) => ref[c] - rd * UP[c]);
  const e1l = Math.hypot(...E1);
  for (let c = 0; c < 3; c++) E1[c] /= e1l;
  const E2 = [UP[1] * E1[2] - UP[2] * E1[1], UP[2] * E1[0] - UP[0] * E1[2], UP[0] * E1[1] - UP[1] * E1[0]];
  function viewProj(aspect) {
    const az = (cam.az * Math.PI) / 180, el = (cam.el * Math.PI) / 180, d = cam.d;
    // A following camera moves its target with the subject (the user's orbit and zoom stay).
    const t = TRACK ? [0, 1, 2].map((c) => cam.t[c] + TRACK[3 * frame + c] - TRACK[c]) : cam.t;
    const dir = [0, 1, 2].map((c) => Math.cos(el) * Math.cos(az) * E1[c] + Math.cos(el) * Math.sin(az) * E2[c] + Math.sin(el) * UP[c]);
    const e = [t[0] + d * dir[0], t[1] + d * dir[1], t[2] + d * dir[2]];
    const f = [t[0] - e[0], t[1] - e[1], t[2] - e[2]];
    const fl = Math.hypot(...f);
    f[0] /= fl; f[1] /= fl; f[2] /= fl;
    const s = [f[1] * UP[2] - f[2] * UP[1], f[2] * UP[0] - f[0] * UP[2], f[0] * UP[1] - f[1] * UP[0]];  // f × up
    const sl = Math.hypot(...s);
    s[0] /= sl; s[1] /= sl; s[2] /= sl;
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

  // Each link's frame (x, y, z as three segments from its origin) at the current frame.
  const LF = new Float32Array(NB * 18);
  function linkFrames() {
    const L = 0.05 * D.size;
    for (let i = 0; i < NB; i++) {
      const o = (frame * NB + i) * 12;
      for (let a = 0; a < 3; a++) {
        const k = (3 * i + a) * 6;
        for (let r = 0; r < 3; r++) {
          LF[k + r] = BP[o + 9 + r];
          LF[k + 3 + r] = BP[o + 9 + r] + L * BP[o + 3 * r + a];
        }
      }
    }
    return LF;
  }

  // ---- drawing one frame
  let frame = 0, contactDrawn = 0;
  const c3 = (arr, i) => [arr[i], arr[i + 1], arr[i + 2]];
  function draw() {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    if (canvas.width !== w || canvas.height !== h) { canvas.width = w; canvas.height = h; }
    gl.viewport(0, 0, w, h);
    gl.clearColor(1, 1, 1, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    gl.uniform1f(U.uA, 1);
    gl.uniformMatrix4fv(U.uVP, false, viewProj(w / h));
    drawLines(GRID, D.colours.grid, gl.LINES);
    for (const [pts, col] of FRAME) drawLines(pts, col, gl.LINES);
    if (shown.has("frames")) drawLines(linkFrames(), [0.4, 0.4, 0.4], gl.LINES);
    for (let j = 0; j < NT; j++)
      if (frame > 0) drawLines(TRAILS[j].subarray(0, 3 * (frame + 1)), D.trails.colour[j], gl.LINE_STRIP);
    if (VIS && shown.has("robot")) drawRobot();
    const masses = shown.has("masses");
    if (NB && masses) drawLines(boxEdges(), D.colours.box, gl.LINES);
    bindMesh(CYL);
    const tubes = (P, n, on, r, col) => {
      if (!on) return;
      for (let i = 0; i < n; i++) {
        const o = (frame * n + i) * 6;
        const m = tubeMatrix(c3(P, o), c3(P, o + 3), r);
        if (m) drawMesh(CYL, m, col, true);
      }
    };
    tubes(LK, NL, shown.has("links"), D.links.radius, D.colours.link);
    tubes(AX, NA, shown.has("axes"), D.axes.radius, D.colours.axis);
    tubes(CU, NC, shown.has("links"), D.cuts.radius, D.colours.cut);
    // Arrows: a shaft (cylinder) now, the heads (cones) after the spheres' mesh is bound.
    const heads = [];
    function shaftOf(a, b, r, col) {
      const k = [0, 1, 2].map((c) => a[c] + 0.8 * (b[c] - a[c]));
      const m = tubeMatrix(a, k, r);
      if (!m) return;
      drawMesh(CYL, m, col, true);
      heads.push([k, b, Math.min(2.5 * r, 0.4 * Math.hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2])), col]);
    }
    if (AR && shown.has("forces")) {
      const a = c3(AR, frame * 6), b = c3(AR, frame * 6 + 3);
      shaftOf(a, b, D.links.radius * 1.2, D.colours.shaking);
    }
    contactDrawn = 0;
    for (let i = 0; CF && shown.has("forces") && i < NK; i++) {
      const o = (frame * NK + i) * 6;
      const a = c3(CF, o), b = c3(CF, o + 3);
      // A point without force (tail = head) draws nothing.
      if (Math.hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]) < 1e-9 * D.size) continue;
      shaftOf(a, b, D.contact.radius, D.colours.contact);
      contactDrawn++;
    }
    bindMesh(SPHERE);
    for (let i = 0; masses && i < NS; i++) {
      const o = (frame * NS + i) * 3;
      drawMesh(SPHERE, sphereMatrix(SP[o], SP[o + 1], SP[o + 2], D.spheres.radius[i]),
        D.spheres.colour[i], true);
    }
    for (let i = 0; shown.has("links") && i < NC; i++) {
      const o = (frame * NC + i) * 6;
      drawMesh(SPHERE, sphereMatrix(CU[o], CU[o + 1], CU[o + 2], D.cuts.radius * 2.2), D.colours.cut, true);
    }
    if (heads.length) bindMesh(CONE);
    for (const [k, b, r, col] of heads) {
      const m = tubeMatrix(k, b, r);
      if (m) drawMesh(CONE, m, col, true);
    }
    // The contact planes after everything opaque: translucent (what lies under a plane shows
    // through, tinted), not writing depth, pushed back a little so their grid lines stay crisp.
    if (PLANE_FILL.length) {
      gl.enable(gl.BLEND);
      // The canvas stays opaque (alpha 1): a page composites its premultiplied colours
      // over the white page, which would wash a translucent fill out to white.
      gl.blendFuncSeparate(gl.SRC_ALPHA, gl.ONE_MINUS_SRC_ALPHA, gl.ZERO, gl.ONE);
      gl.depthMask(false);
      gl.enable(gl.POLYGON_OFFSET_FILL);
      gl.polygonOffset(1, 1);
      gl.uniform1f(U.uA, 0.28);
      drawLines(PLANE_FILL, PLANE_RGB, gl.TRIANGLES);
      gl.uniform1f(U.uA, 1);
      gl.disable(gl.POLYGON_OFFSET_FILL);
      gl.depthMask(true);
      gl.disable(gl.BLEND);
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
  if (hash.has("show")) { shown.clear(); for (const n of hash.get("show").split(",")) if (n) shown.add(n); }
  const present = { robot: !!VIS, masses: NS > 0, links: NL + NC > 0, axes: NA > 0, frames: NB > 0, forces: !!AR || NK > 0 };
  for (const [name, label] of Object.entries(LAYERS)) {
    if (!present[name]) continue;
    const box = document.createElement("input");
    box.type = "checkbox"; box.id = "show-" + name; box.checked = shown.has(name);
    box.onchange = () => { if (box.checked) shown.add(name); else shown.delete(name); if (!playing) draw(); };
    const lab = document.createElement("label");
    lab.append(box, " " + label);
    $("layers").append(lab);
  }
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
  window.__pmd = { frame: () => frame, boxEdges: () => Array.from(boxEdges()),
    shown: () => Array.from(shown).sort(), contactArrows: () => contactDrawn, planes: () => PLANES.length, triangles: () => (VIS ? VIS.instances.reduce((n, i) => n + ROBOT[i.mesh].n / 3, 0) : 0) };
  window.__status = "ok";
  $("status").textContent = window.__errors.length ? "error: " + window.__errors.join("; ") : "";
  document.title = (window.__errors.length ? "pmd error: " + window.__errors.join("; ") : "pmd ok") +
    " frame=" + frame + " size=" + canvas.width + "x" + canvas.height;
  setPlaying(playing);
})();
