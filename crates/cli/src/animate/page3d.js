// mstar animate: the 3-D page's renderer (Canvas 2-D, no library).
// Every frame is drawn from scratch: the ground grid first, then every face
// and line piece of the scene sorted far to near (the painter's algorithm),
// the joint points last. Each body is a box shaded by the angle of its faces
// to a light that moves with the camera (Lambert). The data: page3d.rs.
(function () {
  'use strict';
  const D = JSON.parse(document.getElementById('frames').textContent);
  const canvas = document.getElementById('view');
  const ctx = canvas.getContext('2d');
  const label = document.getElementById('time');
  const slider = document.getElementById('slider');
  const button = document.getElementById('play');
  const speed = document.getElementById('speed');
  const T = D.t, N = T.length, span = N > 0 ? T[N - 1] - T[0] : 0;
  const R = D.r, C = D.c;
  const W = canvas.width, H = canvas.height;
  const AXIS = ['#d62728', '#2ca02c', '#1f5fd6'];
  const INK = '#333333';
  const deg = Math.PI / 180;

  // The camera: yaw about z, elevation, zoom, and a pan offset (m).
  const cam = { yaw: D.v[0] * deg, pitch: D.v[1] * deg, zoom: 1, pan: [0, 0, 0] };
  function resetCamera() {
    cam.yaw = D.v[0] * deg; cam.pitch = D.v[1] * deg; cam.zoom = 1; cam.pan = [0, 0, 0];
  }

  // Vectors.
  const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const norm = (a) => mul(a, 1 / (Math.sqrt(dot(a, a)) || 1));

  // The rotation matrix A(p) (body to global) of Euler parameters p,
  // normalized first (the page's are rounded, interpolated ones shorter).
  function rotation(q) {
    const n = Math.hypot(q[0], q[1], q[2], q[3]) || 1;
    const e0 = q[0] / n, e1 = q[1] / n, e2 = q[2] / n, e3 = q[3] / n;
    return [
      [e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3, 2 * (e1 * e2 - e0 * e3), 2 * (e1 * e3 + e0 * e2)],
      [2 * (e1 * e2 + e0 * e3), e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3, 2 * (e2 * e3 - e0 * e1)],
      [2 * (e1 * e3 - e0 * e2), 2 * (e2 * e3 + e0 * e1), e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3],
    ];
  }
  const apply = (A, s) => [dot(A[0], s), dot(A[1], s), dot(A[2], s)];

  // Each body's position r and rotation A in frame i.
  function poses(i) {
    const f = D.f[i], out = [];
    let j = 0;
    D.b.forEach(function (b) {
      const r = [f[j], f[j + 1], f[j + 2]];
      j += 3;
      let A = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
      if (b[0]) { A = rotation(f.slice(j, j + 4)); j += 4; }
      out.push({ r: r, A: A });
    });
    return out;
  }

  // The camera's axes: right, up, and w toward the eye.
  function basis() {
    const cy = Math.cos(cam.yaw), sy = Math.sin(cam.yaw);
    const cp = Math.cos(cam.pitch), sp = Math.sin(cam.pitch);
    const w = [cp * sy, -cp * cy, sp];
    const right = [cy, sy, 0];
    const up = [w[1] * right[2] - w[2] * right[1], w[2] * right[0] - w[0] * right[2],
      w[0] * right[1] - w[1] * right[0]];
    return { right: right, up: up, w: w };
  }

  // A world point on the canvas: [x px, y px, depth (larger: farther)].
  function projector() {
    const b = basis(), dist = 4 * R;
    const k = cam.zoom * 0.42 * Math.min(W, H) / R;
    const target = add(C, cam.pan);
    const eye = add(target, mul(b.w, dist));
    return {
      basis: b, eye: eye, k: k,
      at: function (p) {
        const d = sub(p, target);
        const z = dot(d, b.w), s = dist / Math.max(dist - z, 1e-3 * dist);
        return [W / 2 + k * s * dot(d, b.right), H / 2 - k * s * dot(d, b.up), dist - z];
      },
    };
  }

  // A body colour shaded by brightness f (0 … 1).
  function shade(hex, f) {
    const c = [1, 3, 5].map(function (i) { return parseInt(hex.substr(i, 2), 16); });
    return 'rgb(' + c.map(function (x) { return Math.round(x * f); }).join(',') + ')';
  }

  // The box's six faces (corner indices; bit i of a corner: sign of half axis i).
  const FACES = [[0, 2, 6, 4], [1, 5, 7, 3], [0, 4, 5, 1], [2, 3, 7, 6], [0, 1, 3, 2], [4, 6, 7, 5]];
  const NORMAL = [[0, -1], [0, 1], [1, -1], [1, 1], [2, -1], [2, 1]];

  // The visible faces of body n's box, as drawing items.
  function boxItems(n, pose, P, light, items) {
    const b = D.b[n];
    const h = [b.slice(2, 5), b.slice(5, 8), b.slice(8, 11)].map(function (a) { return apply(pose.A, a); });
    const corners = [];
    for (let c = 0; c < 8; c++) {
      let p = pose.r;
      for (let i = 0; i < 3; i++) p = add(p, mul(h[i], (c >> i) & 1 ? 1 : -1));
      corners.push(p);
    }
    FACES.forEach(function (face, k) {
      const normal = norm(mul(h[NORMAL[k][0]], NORMAL[k][1]));
      const centre = mul(face.reduce(function (s, c) { return add(s, corners[c]); }, [0, 0, 0]), 0.25);
      if (dot(normal, sub(P.eye, centre)) <= 0) return; // facing away
      const pts = face.map(function (c) { return P.at(corners[c]); });
      const f = 0.3 + 0.7 * Math.max(0, dot(normal, light));
      items.push({ depth: P.at(centre)[2], kind: 'face', pts: pts, fill: shade(b[1], f) });
    });
  }

  // A line cut in pieces, each sorted on its own (an axis through a box
  // shows where it leaves the box).
  function lineItems(a, b, colour, width, P, items) {
    const pieces = 6;
    for (let i = 0; i < pieces; i++) {
      const p = P.at(add(a, mul(sub(b, a), i / pieces)));
      const q = P.at(add(a, mul(sub(b, a), (i + 1) / pieces)));
      items.push({ depth: 0.5 * (p[2] + q[2]), kind: 'line', pts: [p, q], stroke: colour, width: width });
    }
  }

  // The ground: a grid in the plane z = 0 around the run's centre, with
  // lines at round multiples of metres, drawn before everything else.
  function grid(P) {
    const step = Math.pow(10, Math.floor(Math.log10(R)));
    const n = Math.ceil(1.5 * R / step);
    const x0 = Math.round(C[0] / step) * step, y0 = Math.round(C[1] / step) * step;
    ctx.strokeStyle = '#dddddd';
    ctx.lineWidth = 1;
    ctx.beginPath();
    for (let i = -n; i <= n; i++) {
      for (const [a, b] of [[[x0 + i * step, y0 - n * step, 0], [x0 + i * step, y0 + n * step, 0]],
        [[x0 - n * step, y0 + i * step, 0], [x0 + n * step, y0 + i * step, 0]]]) {
        const p = P.at(a), q = P.at(b);
        ctx.moveTo(p[0], p[1]);
        ctx.lineTo(q[0], q[1]);
      }
    }
    ctx.stroke();
  }

  // Frame i drawn from scratch.
  function draw(i) {
    const P = projector(), B = P.basis;
    const light = norm(add(add(mul(B.right, -0.4), mul(B.up, 0.6)), B.w));
    ctx.fillStyle = '#ffffff';
    ctx.fillRect(0, 0, W, H);
    grid(P);
    const items = [];
    const pose = poses(i);
    const dotAt = D.m.map(function (m) {
      return m[0] < 0 ? m.slice(1, 4) : add(pose[m[0]].r, apply(pose[m[0]].A, m.slice(1, 4)));
    });
    for (let a = 0; a < 3; a++) {
      const e = [0, 0, 0];
      e[a] = 0.25 * R;
      lineItems([0, 0, 0], e, AXIS[a], 2, P, items);
    }
    pose.forEach(function (p, n) {
      const b = D.b[n];
      if (!b[0]) {
        const q = P.at(p.r);
        items.push({ depth: q[2], kind: 'ball', at: q, r: 0.035 * R, fill: b[1] });
        return;
      }
      boxItems(n, p, P, light, items);
      // Each body axis out of the box by 0.3 of its largest half side: the
      // box reaches Σ_i |h_i · e_a| along body axis a.
      const h = [b.slice(2, 5), b.slice(5, 8), b.slice(8, 11)];
      const half = h.map(function (v) { return Math.hypot(v[0], v[1], v[2]); });
      const extra = 0.3 * Math.max(half[0], half[1], half[2]) + 0.01 * R;
      for (let a = 0; a < 3; a++) {
        const reach = Math.abs(h[0][a]) + Math.abs(h[1][a]) + Math.abs(h[2][a]);
        const tip = add(p.r, mul([p.A[0][a], p.A[1][a], p.A[2][a]], reach + extra));
        lineItems(p.r, tip, AXIS[a], 2, P, items);
      }
    });
    // Each body's joint points joined to its centre of mass (a top's stem).
    D.m.forEach(function (m, j) {
      if (m[0] >= 0) lineItems(pose[m[0]].r, dotAt[j], INK, 2, P, items);
    });
    D.e.forEach(function (e) {
      lineItems(dotAt[e[0]], dotAt[e[1]], e[2] ? '#777777' : INK, e[2] ? 1.5 : 3, P, items);
    });
    items.sort(function (a, b) { return b.depth - a.depth; });
    items.forEach(function (it) { paint(it, P); });
    // The joint points last, over everything (they lie at the ends of
    // bodies, inside their boxes), far ones first.
    dotAt.map(P.at).sort(function (a, b) { return b[2] - a[2]; }).forEach(function (q) {
      paint({ kind: 'ball', at: q, r: 0.018 * R, fill: INK }, P);
    });
  }

  // One item on the canvas.
  function paint(it, P) {
    if (it.kind === 'face') {
      ctx.beginPath();
      ctx.moveTo(it.pts[0][0], it.pts[0][1]);
      for (let k = 1; k < it.pts.length; k++) ctx.lineTo(it.pts[k][0], it.pts[k][1]);
      ctx.closePath();
      ctx.fillStyle = it.fill;
      ctx.fill();
      ctx.strokeStyle = 'rgba(0,0,0,0.35)';
      ctx.lineWidth = 1;
      ctx.stroke();
    } else if (it.kind === 'line') {
      ctx.beginPath();
      ctx.moveTo(it.pts[0][0], it.pts[0][1]);
      ctx.lineTo(it.pts[1][0], it.pts[1][1]);
      ctx.strokeStyle = it.stroke;
      ctx.lineWidth = it.width;
      ctx.lineCap = 'round';
      ctx.stroke();
    } else {
      const r = Math.max(2, it.r * P.k * 4 * R / it.at[2]);
      ctx.beginPath();
      ctx.arc(it.at[0], it.at[1], r, 0, 2 * Math.PI);
      ctx.fillStyle = it.fill;
      ctx.fill();
      ctx.strokeStyle = '#ffffff';
      ctx.lineWidth = 1;
      ctx.stroke();
    }
  }

  // Time: plays the frames by simulated time at the chosen speed, looping.
  let k = 0, simT = N > 0 ? T[0] : 0, last = null, playing = N > 1 && span > 0, dirty = true;
  function show(i) {
    k = i;
    label.textContent = 't = ' + T[i].toFixed(3) + ' s';
    slider.value = String(i);
    dirty = true;
  }
  function frameAt(t) {
    let lo = 0, hi = N - 1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (T[mid] <= t) lo = mid; else hi = mid - 1;
    }
    return lo;
  }
  function setPlaying(on) {
    playing = on && N > 1 && span > 0;
    last = null;
    button.textContent = playing ? 'Pause' : 'Play';
  }
  function tick(now) {
    if (playing) {
      if (last !== null) {
        simT += (now - last) / 1000 * Number(speed.value);
        if (simT > T[N - 1]) simT = T[0] + (simT - T[0]) % span;
        const i = frameAt(simT);
        if (i !== k) show(i);
      }
      last = now;
    }
    if (dirty && N > 0) { draw(k); dirty = false; }
    requestAnimationFrame(tick);
  }

  // The mouse: drag turns, shift-drag or right-drag pans, the wheel zooms.
  let drag = null;
  canvas.addEventListener('pointerdown', function (ev) {
    drag = { x: ev.clientX, y: ev.clientY, pan: ev.shiftKey || ev.button === 2 };
    try { canvas.setPointerCapture(ev.pointerId); } catch (e) { /* a synthetic pointer */ }
    ev.preventDefault();
  });
  canvas.addEventListener('pointermove', function (ev) {
    if (!drag) return;
    const dx = ev.clientX - drag.x, dy = ev.clientY - drag.y;
    drag.x = ev.clientX; drag.y = ev.clientY;
    if (drag.pan) {
      const P = projector(), B = P.basis;
      cam.pan = add(cam.pan, add(mul(B.right, -dx / P.k), mul(B.up, dy / P.k)));
    } else {
      cam.yaw -= dx * 0.01;
      cam.pitch = Math.max(-Math.PI / 2, Math.min(Math.PI / 2, cam.pitch + dy * 0.01));
    }
    dirty = true;
  });
  function endDrag() { drag = null; }
  canvas.addEventListener('pointerup', endDrag);
  canvas.addEventListener('pointercancel', endDrag);
  canvas.addEventListener('contextmenu', function (ev) { ev.preventDefault(); });
  canvas.addEventListener('wheel', function (ev) {
    cam.zoom = Math.max(0.05, Math.min(50, cam.zoom * Math.exp(-ev.deltaY * 0.001)));
    dirty = true;
    ev.preventDefault();
  }, { passive: false });

  button.addEventListener('click', function () { setPlaying(!playing); });
  document.getElementById('reset').addEventListener('click', function () { resetCamera(); dirty = true; });
  slider.addEventListener('input', function () {
    const i = Number(slider.value);
    simT = T[i];
    show(i);
  });

  // A view asked for in the address: '#t=0.5' shows that time, paused;
  // '#drag=dx,dy' drags the mouse by (dx, dy) px through the same events a
  // hand on the mouse sends (for screenshots of a turned view).
  function fromAddress() {
    const hash = new URLSearchParams(location.hash.slice(1));
    if (hash.has('t') && N > 0) {
      const t = Number(hash.get('t'));
      if (isFinite(t)) { simT = t; show(frameAt(t)); setPlaying(false); }
    }
    if (hash.has('drag')) {
      const d = hash.get('drag').split(',').map(Number);
      if (d.length === 2 && d.every(isFinite)) {
        const box = canvas.getBoundingClientRect();
        const x = box.left + box.width / 2, y = box.top + box.height / 2;
        const send = function (type, px, py) {
          canvas.dispatchEvent(new PointerEvent(type, {
            clientX: px, clientY: py, pointerId: 1, button: 0, buttons: 1, bubbles: true,
          }));
        };
        send('pointerdown', x, y);
        send('pointermove', x + d[0], y + d[1]);
        send('pointerup', x + d[0], y + d[1]);
      }
    }
  }

  if (N > 0) show(0);
  setPlaying(playing);
  fromAddress();
  requestAnimationFrame(tick);
})();
