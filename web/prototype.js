// The virtual prototype of `hapsyn view`: a motion study replayed (the manipulator following the
// hand at the configuration its IK picks, per-joint bars of |qdot|/limit and |tau|/limit, the
// infeasible samples marked on the timeline). It draws into app.js's scene (window.hapsynScene)
// and keeps its state on window.hapsynView.replay for tests:
//   {ready, available, reason, frames, frame, sample, time, clock (the replay's clock [s]),
//    wallPlayed (the page's clock while it last played [s]), playing, speed, q, qdotRatio,
//    tauRatio, feasible, infeasible (the scene samples marked infeasible), trajectory,
//    seek(frame), seekSample(sample), play(), pause(), setSpeed(x)};
// its live mode (button "live": the frames of the poses a tracker bridge sends to /live, received
// on the WebSocket /live/watch) on window.hapsynView.live:
//   {on, connected, frames, t, status, q, qdotRatio, tauRatio, feasible, rates, tip, start(), stop()};
// and WebXR (button "XR" where a headset is available) on window.hapsynView.xr:
//   {supported, active, shoulder, sent, message(t, p, q), baseToXr(p), send(t, p, q) -> frame}.
import * as THREE from 'three';

const SPEEDS = [1, 2, 4];
const BAR_FULL = 2;  // a bar's full width is twice the limit: the limit sits in the middle

const live = { on: false, connected: false, frames: 0, t: null, status: null, q: null, qdotRatio: null, tauRatio: null,
               feasible: null, rates: null, tip: null };
const xr = { supported: false, active: false, shoulder: [0.2, 1.35, 0], sent: 0 };
const replay = {
  ready: false, available: false, reason: null, frames: 0, frame: -1, sample: null, time: 0, playing: false, speed: 1,
  wallPlayed: 0, clock: 0,
  q: [], qdotRatio: [], tauRatio: [], feasible: null, infeasible: [], trajectory: null,
};
(window.hapsynView || (window.hapsynView = {})).replay = replay;
window.hapsynView.live = live;
window.hapsynView.xr = xr;

const STYLE = `
  #prototype { position: absolute; left: 10px; right: 10px; bottom: 10px; padding: 8px 12px; background: rgba(255,255,255,0.92);
               border: 1px solid #ccc; border-radius: 6px; }
  #prototype .row { display: flex; align-items: center; gap: 8px; }
  #prototype input[type=range] { flex: 1; }
  #proto-timeline { width: 100%; height: 18px; display: block; margin-top: 4px; border: 1px solid #bbb; }
  #proto-bars { position: absolute; top: 10px; right: 10px; width: 260px; padding: 8px 10px; background: rgba(255,255,255,0.92);
                border: 1px solid #ccc; border-radius: 6px; }
  #proto-bars .bar { position: relative; height: 9px; background: #e6e6e6; margin: 1px 0 3px; }
  #proto-bars .fill { position: absolute; left: 0; top: 0; bottom: 0; background: #3b7a57; }
  #proto-bars .fill.over { background: #c0392b; }
  #proto-bars .limit { position: absolute; left: 50%; top: -2px; bottom: -2px; width: 1px; background: #222; }
  #proto-bars .joint { display: flex; justify-content: space-between; }
  .proto-dim { color: #666; }
`;

function element(tag, attributes = {}, parent = null) {
  const e = document.createElement(tag);
  Object.assign(e, attributes);
  if (parent) parent.appendChild(e);
  return e;
}

// Global clock: the trajectories one after the other, each from its first time stamp.
function globalTimes(doc) {
  const g = new Float64Array(doc.frames);
  let base = 0;
  for (let f = 0; f < doc.frames;) {
    const t = doc.trajectory[f], first = f;
    while (f < doc.frames && doc.trajectory[f] === t) ++f;
    const t0 = doc.time[first], last = f - 1;
    for (let k = first; k <= last; ++k) g[k] = base + doc.time[k] - t0;
    const step = last > first ? (doc.time[last] - doc.time[first]) / (last - first) : 0;
    base = g[last] + step;
  }
  return g;
}

// The last frame whose global time is <= t.
function frameAt(g, t) {
  let lo = 0, hi = g.length - 1;
  while (lo < hi) {
    const mid = (lo + hi + 1) >> 1;
    if (g[mid] <= t) lo = mid; else hi = mid - 1;
  }
  return lo;
}

// Links as capsules from pooled meshes: a frame's polylines reuse the meshes of the last.
class Arm {
  constructor(scene, radius) {
    this.group = new THREE.Group();
    scene.add(this.group);
    this.radius = radius;
    this.link = new THREE.MeshStandardMaterial({ color: 0xc8553d, metalness: 0.1, roughness: 0.6 });
    this.joint = new THREE.MeshStandardMaterial({ color: 0x2d3142, metalness: 0.1, roughness: 0.5 });
    this.sphere = new THREE.SphereGeometry(radius * 1.4, 16, 12);
    this.cylinder = new THREE.CylinderGeometry(radius, radius, 1, 16);
    this.spheres = [];
    this.cylinders = [];
    this.up = new THREE.Vector3(0, 1, 0);
  }

  mesh(pool, index, geometry, material) {
    if (!pool[index]) {
      pool[index] = new THREE.Mesh(geometry, material);
      this.group.add(pool[index]);
    }
    pool[index].visible = true;
    return pool[index];
  }

  // polylines: arrays of THREE.Vector3
  show(polylines) {
    let s = 0, c = 0;
    for (const points of polylines) {
      for (let i = 0; i < points.length; ++i) {
        this.mesh(this.spheres, s++, this.sphere, this.joint).position.copy(points[i]);
        if (i === 0) continue;
        const along = new THREE.Vector3().subVectors(points[i], points[i - 1]);
        const length = along.length();
        if (length === 0) continue;
        const link = this.mesh(this.cylinders, c++, this.cylinder, this.link);
        link.position.addVectors(points[i], points[i - 1]).multiplyScalar(0.5);
        link.quaternion.setFromUnitVectors(this.up, along.divideScalar(length));
        link.scale.set(1, length, 1);
      }
    }
    for (let k = s; k < this.spheres.length; ++k) this.spheres[k].visible = false;
    for (let k = c; k < this.cylinders.length; ++k) this.cylinders[k].visible = false;
  }
}

// Per-joint bars: |qdot|/limit and |tau|/limit, red beyond the limit.
class Bars {
  constructor(parent, joints, title) {
    this.root = element('div', { id: 'proto-bars' }, parent);
    element('div', { innerHTML: `<b>${title}</b> <span class="proto-dim">|value| / limit; line: the limit</span>` }, this.root);
    this.rows = [];
    for (let j = 0; j < joints; ++j) {
      const row = {};
      for (const kind of ['qdot', 'tau']) {
        const label = element('div', { className: 'joint' }, this.root);
        element('span', { textContent: `joint ${j + 1} ${kind === 'qdot' ? '|qdot|' : '|tau|'}` }, label);
        row[kind + 'Text'] = element('span', { className: 'proto-dim' }, label);
        const bar = element('div', { className: 'bar' }, this.root);
        row[kind] = element('div', { className: 'fill' }, bar);
        element('div', { className: 'limit' }, bar);
      }
      this.rows.push(row);
    }
  }

  show(qdot, tau) {
    this.rows.forEach((row, j) => {
      for (const [kind, values] of [['qdot', qdot], ['tau', tau]]) {
        const v = values[j];
        const known = v !== null && v !== undefined;
        row[kind].style.width = known ? `${Math.min(v / BAR_FULL, 1) * 100}%` : '0';
        row[kind].classList.toggle('over', known && v > 1);
        row[kind + 'Text'].textContent = known ? v.toFixed(3) : '–';
      }
    });
  }
}

function drawTimeline(canvas, doc, g) {
  const width = canvas.clientWidth || 800, height = canvas.clientHeight || 18;
  canvas.width = width;
  canvas.height = height;
  const context = canvas.getContext('2d');
  context.fillStyle = '#f0f0f0';
  context.fillRect(0, 0, width, height);
  const total = Math.max(g[g.length - 1], 1e-9);
  const x = f => Math.min(width - 1, Math.floor(g[f] / total * width));
  context.fillStyle = '#c0392b';
  if (doc.feasible) for (let f = 0; f < doc.frames; ++f) if (doc.feasible[f] === 0) context.fillRect(x(f), 0, 1, height);
  context.fillStyle = '#444';
  for (let f = 1; f < doc.frames; ++f) if (doc.trajectory[f] !== doc.trajectory[f - 1]) context.fillRect(x(f), 0, 1, height);
}

function startReplay(three, doc) {
  const g = globalTimes(doc);
  const J = doc.joints;
  const polylines = [];  // per polyline: its first point's index
  let point = 0;
  for (const size of doc.polyline_sizes) {
    polylines.push(point);
    point += size;
  }
  const arm = new Arm(three.scene, three.size * 0.006);
  const hand = new THREE.Mesh(new THREE.SphereGeometry(three.size * 0.012, 16, 12),
                              new THREE.MeshStandardMaterial({ color: 0x1f77b4, transparent: true, opacity: 0.7 }));
  three.scene.add(hand);
  three.mechanism.visible = false;  // the replay draws the mechanism

  element('style', { textContent: STYLE }, document.head);
  const panel = element('div', { id: 'prototype' }, document.body);
  const row = element('div', { className: 'row' }, panel);
  const play = element('button', { id: 'proto-play', textContent: 'play' }, row);
  const speed = element('select', { id: 'proto-speed' }, row);
  for (const s of SPEEDS) element('option', { value: String(s), textContent: `x${s}` }, speed);
  const scrubber = element('input', { id: 'proto-scrubber', type: 'range', min: '0', max: String(doc.frames - 1), step: '1', value: '0' }, row);
  const label = element('span', { id: 'proto-time' }, row);
  const liveButton = element('button', { id: 'proto-live', textContent: 'live', title: 'follow the poses a tracker bridge sends to /live' }, row);
  const timeline = element('canvas', { id: 'proto-timeline' }, panel);
  const marked = doc.feasible ? doc.feasible.filter(v => v === 0).length : 0;
  element('div', {
    className: 'proto-dim',
    textContent: doc.feasible
      ? `red: the ${marked} of ${doc.frames} samples motion_feasibility marks infeasible (${doc.checks.join(', ')}); dark: a new trajectory`
      : 'no motion_feasibility metric in this study: nothing is marked',
  }, panel);
  const bars = new Bars(document.body, J, 'joint rates and torques');

  replay.infeasible = [];
  if (doc.feasible) for (let f = 0; f < doc.frames; ++f) if (doc.feasible[f] === 0) replay.infeasible.push(doc.sample[f]);
  const frameOf = new Map(doc.sample.map((s, f) => [s, f]));
  let clock = 0, last = null;

  const show = f => {
    replay.frame = f;
    replay.sample = doc.sample[f];
    replay.time = doc.time[f];
    replay.trajectory = doc.trajectories[doc.trajectory[f]];
    replay.q = doc.q.slice(f * J, f * J + J);
    replay.qdotRatio = doc.qdot_ratio.slice(f * J, f * J + J);
    replay.tauRatio = doc.tau_ratio.slice(f * J, f * J + J);
    replay.feasible = doc.feasible ? doc.feasible[f] : null;
    const lines = [];
    for (let k = doc.frame_polylines[f]; k < doc.frame_polylines[f + 1]; ++k) {
      const points = [];
      for (let i = 0; i < doc.polyline_sizes[k]; ++i) {
        const p = 3 * (polylines[k] + i);
        points.push(new THREE.Vector3(doc.points[p], doc.points[p + 1], doc.points[p + 2]));
      }
      lines.push(points);
    }
    arm.show(lines);
    const p = 3 * replay.sample, positions = three.samples.positions;
    hand.position.set(positions[p], positions[p + 1], positions[p + 2]);
    bars.show(replay.qdotRatio, replay.tauRatio);
    scrubber.value = String(f);
    label.textContent = `${replay.trajectory} t = ${replay.time.toFixed(3)} s (sample ${replay.sample}, ${doc.status[f]}` +
      (replay.feasible === 0 ? ', infeasible)' : ')');
  };
  const seek = f => {
    const frame = Math.max(0, Math.min(doc.frames - 1, Math.round(f)));
    clock = g[frame];
    replay.clock = clock;
    show(frame);
    return frame;
  };
  const tick = now => {
    if (!replay.playing) return;
    if (last !== null) {
      const seconds = (now - last) / 1000;
      clock += seconds * replay.speed;
      replay.wallPlayed += seconds;  // the page's own clock while playing, for tests
    }
    replay.clock = clock;
    last = now;
    if (clock >= g[g.length - 1]) {
      clock = g[g.length - 1];
      replay.pause();
    }
    const f = frameAt(g, clock);
    if (f !== replay.frame) show(f);
    if (replay.playing) requestAnimationFrame(tick);
  };
  replay.seek = seek;
  replay.seekSample = s => (frameOf.has(s) ? seek(frameOf.get(s)) : -1);
  replay.play = () => {
    if (replay.playing) return;
    live.stop();
    if (replay.frame >= doc.frames - 1) seek(0);
    replay.playing = true;
    replay.wallPlayed = 0;
    play.textContent = 'pause';
    last = null;
    requestAnimationFrame(tick);
  };
  replay.pause = () => {
    replay.playing = false;
    play.textContent = 'play';
  };
  replay.setSpeed = x => {
    if (!SPEEDS.includes(x)) return false;
    replay.speed = x;
    speed.value = String(x);
    return true;
  };
  // Live: every frame the server computes for a bridge's poses, drawn as it comes.
  let socket = null;
  const showLive = frame => {
    const lines = frame.segments.map(s => s.points.map(p => new THREE.Vector3(p[0], p[1], p[2])));
    arm.show(lines);
    hand.position.set(frame.position[0], frame.position[1], frame.position[2]);
    Object.assign(live, {
      frames: live.frames + 1, t: frame.t, status: frame.status, q: frame.q, qdotRatio: frame.qdot_ratio,
      tauRatio: frame.tau_ratio, feasible: frame.feasible, rates: frame.rates,
      tip: lines.length ? lines[lines.length - 1][lines[lines.length - 1].length - 1].toArray() : null,
    });
    bars.show(frame.qdot_ratio || [], frame.tau_ratio || []);
    label.textContent = `live t = ${frame.t.toFixed(3)} s, ${frame.status}` +
      (frame.feasible === 0 ? ', infeasible' : '') + `; rates: ${frame.rates}`;
  };
  live.start = () => {
    if (live.on) return;
    replay.pause();
    live.on = true;
    liveButton.textContent = 'stop live';
    label.textContent = 'live: waiting for poses on /live';
    socket = new WebSocket(`ws://${location.host}/live/watch`);
    socket.onopen = () => { live.connected = true; };
    socket.onclose = () => { live.connected = false; };
    socket.onmessage = event => {
      const frame = JSON.parse(event.data);
      if (live.on && !frame.error) showLive(frame);
    };
  };
  live.stop = () => {
    if (!live.on) return;
    live.on = false;
    liveButton.textContent = 'live';
    if (socket) socket.close();
    socket = null;
    show(replay.frame);
  };
  liveButton.addEventListener('click', () => (live.on ? live.stop() : live.start()));
  startXr(three, doc, row, showLive);
  play.addEventListener('click', () => (replay.playing ? replay.pause() : replay.play()));
  speed.addEventListener('change', () => replay.setSpeed(Number(speed.value)));
  scrubber.addEventListener('input', () => {
    live.stop();
    seek(Number(scrubber.value));
  });
  drawTimeline(timeline, doc, g);
  window.addEventListener('resize', () => drawTimeline(timeline, doc, g));
  seek(0);
}

// WebXR: a headset's controller drives the prototype. WebXR's reference space has the axes of
// the arm model's shoulder frame S (x to the right, y up, z backwards), so the controller's grip
// pose relative to the user's shoulder (xr.shoulder, set by pressing the trigger with the
// controller at the right shoulder) is the live message's palm pose, sent to /live; the study's
// scene is placed around the user by S's pose in the base frame (/api/replay shoulder_frame).
function startXr(three, doc, row, showLive) {
  const frame = doc.shoulder_frame;
  if (!frame) return;
  const C = frame.C_S_B, x0 = frame.x_S_B;
  // x_XR = shoulder + C_S_B^T (x_B - x_S_B)
  xr.baseToXr = p => {
    const d = [p[0] - x0[0], p[1] - x0[1], p[2] - x0[2]];
    return [0, 1, 2].map(k => xr.shoulder[k] + C[0][k] * d[0] + C[1][k] * d[1] + C[2][k] * d[2]);
  };
  xr.message = (t, p, q) => ({ t, position: [0, 1, 2].map(k => p[k] - xr.shoulder[k]), orientation: q });
  let socket = null, pending = null;
  const open = () => new Promise((resolve, reject) => {
    if (socket && socket.readyState === WebSocket.OPEN) return resolve(socket);
    socket = new WebSocket(`ws://${location.host}/live`);
    socket.onopen = () => resolve(socket);
    socket.onerror = () => reject(new Error('/live: the WebSocket failed'));
    socket.onmessage = event => {
      const answer = JSON.parse(event.data);
      if (!answer.error) showLive(answer);
      if (pending) pending(answer);
      pending = null;
    };
  });
  // One pose in flight at a time: a headset's frames come faster than they need to be sent.
  xr.send = async (t, p, q) => {
    if (pending) return null;
    const ws = await open();
    return new Promise(resolve => {
      pending = resolve;
      ws.send(JSON.stringify(xr.message(t, p, q)));
      ++xr.sent;
    });
  };
  if (!navigator.xr) return;
  navigator.xr.isSessionSupported('immersive-vr').then(supported => {
    xr.supported = supported;
    if (!supported) return;
    const button = element('button', { id: 'proto-xr', textContent: 'XR' }, row);
    button.addEventListener('click', async () => {
      const renderer = three.renderer;
      const session = await navigator.xr.requestSession('immersive-vr', { optionalFeatures: ['local-floor'] });
      renderer.xr.enabled = true;
      renderer.xr.setReferenceSpaceType('local-floor');
      await renderer.xr.setSession(session);
      xr.active = true;
      replay.pause();
      // The study around the user: B placed so that S sits at the shoulder.
      const root = three.scene;
      const m = new THREE.Matrix4().set(C[0][0], C[1][0], C[2][0], 0, C[0][1], C[1][1], C[2][1], 0,
                                        C[0][2], C[1][2], C[2][2], 0, 0, 0, 0, 1);
      const o = xr.baseToXr([0, 0, 0]);
      m.setPosition(o[0], o[1], o[2]);
      root.matrixAutoUpdate = false;
      root.matrix.copy(m);
      const grip = renderer.xr.getControllerGrip(0);
      const controller = renderer.xr.getController(0);
      controller.addEventListener('selectstart', () => { xr.shoulder = grip.position.toArray(); });
      const loop = (time, xrFrame) => {
        if (!xr.active) return;
        if (grip.visible !== false) {
          const q = grip.quaternion;
          xr.send(time / 1000, grip.position.toArray(), [q.w, q.x, q.y, q.z]);
        }
        session.requestAnimationFrame(loop);
      };
      session.requestAnimationFrame(loop);
      session.addEventListener('end', () => {
        xr.active = false;
        root.matrixAutoUpdate = true;
        root.matrix.identity();
        renderer.xr.enabled = false;
      });
    });
  });
}

async function start(three) {
  try {
    const response = await fetch('/api/replay');
    if (!response.ok) throw new Error(`/api/replay: HTTP ${response.status}`);
    const doc = await response.json();
    replay.available = doc.available;
    if (doc.available) {
      replay.frames = doc.frames;
      startReplay(three, doc);
    } else {
      replay.reason = doc.reason;
    }
  } catch (e) {
    replay.error = String(e && e.message ? e.message : e);
  }
  replay.ready = true;
}

if (window.hapsynScene) start(window.hapsynScene);
else window.addEventListener('hapsyn-scene', e => start(e.detail), { once: true });
