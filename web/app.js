// The page of `hapsyn view`: the study's mechanism at its design, its scene frame and gravity,
// and the samples as a point cloud coloured by a chosen local value. Its state is on
// window.hapsynView for tests: {ready, error, pointCount, objective, colourRange, segments,
// drawnSegments, human, meshes, meshBoxes, meshErrors, meshesDone} (the meshes: meshes.js);
// front.js and plots.js add theirs (a result's front, runs, sweep or comparison).
import * as THREE from 'three';
import { OrbitControls } from '/OrbitControls.js';
import { humanFigure, figurePoints } from '/figure.js';
import { addMeshes } from '/meshes.js';
import { setupFront } from '/front.js';
import { scatter3d } from '/front3d.js';
import { setupBatch, setupRuns } from 'hapsyn/plots.js';

const state = { ready: false, error: null, pointCount: 0, objective: null, colourRange: null, segments: 0, columns: [],
                human: null };
window.hapsynView = state;

// Viridis at five stops: perceptually even, readable in grey.
const STOPS = [[0.267, 0.005, 0.329], [0.231, 0.322, 0.545], [0.129, 0.569, 0.549], [0.369, 0.788, 0.384], [0.993, 0.906, 0.144]];
const NO_VALUE = [0.72, 0.72, 0.72];

function colourAt(t) {
  const x = Math.min(Math.max(t, 0), 1) * (STOPS.length - 1);
  const i = Math.min(Math.floor(x), STOPS.length - 2), f = x - i;
  return STOPS[i].map((a, k) => a + f * (STOPS[i + 1][k] - a));
}

async function getJson(url) {
  // A report (hapsyn report) carries its documents in the page.
  const inline = document.querySelector(`script[type="application/json"][data-route="${url}"]`);
  if (inline) return JSON.parse(inline.textContent);
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
  return response.json();
}

function format(v) {
  return v === null || v === undefined ? '–' : Number(v).toPrecision(4);
}

// The range of a column over the samples that have a value.
function rangeOf(values) {
  let lo = Infinity, hi = -Infinity;
  for (const v of values) {
    if (v === null) continue;
    lo = Math.min(lo, v);
    hi = Math.max(hi, v);
  }
  return lo <= hi ? [lo, hi] : null;
}

function pointCloud(samples) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(samples.positions), 3));
  geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(samples.count * 3), 3));
  const material = new THREE.PointsMaterial({ size: 4, sizeAttenuation: false, vertexColors: true });
  return new THREE.Points(geometry, material);
}

function colourPoints(points, column) {
  const colours = points.geometry.getAttribute('color');
  const range = column ? rangeOf(column.values) : null;
  for (let i = 0; i < colours.count; ++i) {
    const v = column ? column.values[i] : null;
    const c = v === null || !range ? NO_VALUE : colourAt(range[1] > range[0] ? (v - range[0]) / (range[1] - range[0]) : 0.5);
    colours.setXYZ(i, c[0], c[1], c[2]);
  }
  colours.needsUpdate = true;
  return range;
}

// A link as a capsule: a cylinder between two points with spheres at the joints.
function mechanism(study, radius) {
  const group = new THREE.Group();
  const linkMaterial = new THREE.MeshStandardMaterial({ color: 0xc8553d, metalness: 0.1, roughness: 0.6 });
  const jointMaterial = new THREE.MeshStandardMaterial({ color: 0x2d3142, metalness: 0.1, roughness: 0.5 });
  const up = new THREE.Vector3(0, 1, 0);
  for (const segment of study.segments) {
    const points = segment.points.map(p => new THREE.Vector3(p[0], p[1], p[2]));
    for (let i = 0; i < points.length; ++i) {
      const joint = new THREE.Mesh(new THREE.SphereGeometry(radius * 1.4, 16, 12), jointMaterial);
      joint.position.copy(points[i]);
      group.add(joint);
      if (i === 0) continue;
      const along = new THREE.Vector3().subVectors(points[i], points[i - 1]);
      const length = along.length();
      if (length === 0) continue;
      const link = new THREE.Mesh(new THREE.CylinderGeometry(radius, radius, length, 16), linkMaterial);
      link.position.addVectors(points[i], points[i - 1]).multiplyScalar(0.5);
      link.quaternion.setFromUnitVectors(up, along.divideScalar(length));
      group.add(link);
    }
  }
  return group;
}

function fillPanel(study, samples) {
  document.getElementById('title').textContent = study.name;
  const design = Object.entries(study.design).map(([k, v]) => `${k} = ${JSON.stringify(v)}`).join(', ');
  document.getElementById('about').textContent =
    `${study.mechanism} on ${study.scene} (${samples.count} samples), ${study.source}; design: ${design}` +
    (study.drawn_sample === null ? '; no reachable sample to draw the mechanism at' : `; drawn at sample ${study.drawn_sample}`);
  const select = document.getElementById('objective');
  samples.columns.forEach((c, i) => {
    const option = document.createElement('option');
    option.value = String(i);
    option.textContent = c.objectives.length ? `${c.name} (${c.objectives.join(', ')})` : c.name;
    select.appendChild(option);
  });
}

function showLegend(column, range) {
  document.getElementById('legend-min').textContent = range ? format(range[0]) : '–';
  document.getElementById('legend-max').textContent = range ? format(range[1]) : '–';
  document.getElementById('legend-unit').textContent = column ? (column.unit ? `[${column.unit}]` : '[-]') : '';
}

function frameCamera(camera, controls, box) {
  const centre = box.getCenter(new THREE.Vector3());
  const size = Math.max(box.getSize(new THREE.Vector3()).length(), 1e-3);
  camera.near = size / 1000;
  camera.far = size * 100;
  camera.position.copy(centre).add(new THREE.Vector3(0.9, -1.3, 0.8).multiplyScalar(size));
  camera.updateProjectionMatrix();
  controls.target.copy(centre);
  controls.update();
}

async function main() {
  const [study, samples, result] = await Promise.all([getJson('/api/study'), getJson('/api/samples'), getJson('/api/result')]);
  const container = document.getElementById('view');
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setSize(container.clientWidth, container.clientHeight);
  container.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf4f4f2);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x888888, 2.0));
  const sun = new THREE.DirectionalLight(0xffffff, 1.5);
  sun.position.set(1, -2, 3);
  scene.add(sun);
  const camera = new THREE.PerspectiveCamera(45, container.clientWidth / container.clientHeight, 0.001, 100);
  camera.up.set(0, 0, 1);  // z up, as the scene frame
  const controls = new OrbitControls(camera, renderer.domElement);

  const points = pointCloud(samples);
  scene.add(points);
  const box = new THREE.Box3().setFromObject(points);
  for (const s of study.segments) for (const p of s.points) box.expandByPoint(new THREE.Vector3(p[0], p[1], p[2]));
  for (const p of figurePoints(study.figure)) box.expandByPoint(new THREE.Vector3(p[0], p[1], p[2]));
  box.expandByPoint(new THREE.Vector3(0, 0, 0));
  const size = Math.max(box.getSize(new THREE.Vector3()).length(), 1e-3);
  let drawn = mechanism(study, size * 0.006);
  scene.add(drawn);
  const meshes = addMeshes(scene, study, drawn, state);
  const human = humanFigure(study.figure);
  if (human) scene.add(human);
  // What the page drew of the human, for tests: the arm's joints and the head.
  state.human = study.figure ? { arm: study.figure.arm, headCentre: study.figure.head_centre, drawn: human !== null } : null;
  scene.add(new THREE.AxesHelper(size * 0.15));
  const g = new THREE.Vector3(...study.gravity).normalize();
  const top = box.max.clone();
  scene.add(new THREE.ArrowHelper(g, new THREE.Vector3(box.min.x, box.min.y, top.z), size * 0.2, 0x1f4e9c));

  fillPanel(study, samples);
  state.pointCount = samples.count;
  state.segments = study.segments.length;
  state.drawnSegments = study.segments;
  setupRuns(result, study.objectives, state);
  setupBatch(result, state);
  // A front point clicked: its design drawn instead (front.js).
  setupFront(result, state, point => {
    scene.remove(drawn);
    drawn.traverse(o => o.geometry && o.geometry.dispose());
    drawn = mechanism(point, size * 0.006);
    scene.add(drawn);
    // A URDF's meshes are placed for the design shown first only: hidden for any other.
    const meshGroup = scene.getObjectByName('meshes');
    if (meshGroup) meshGroup.visible = false;
    state.segments = point.segments.length;
    state.drawnSegments = point.segments;
  }, scatter3d);
  state.columns = samples.columns.map(c => c.name);
  const select = document.getElementById('objective');
  const choose = index => {
    const column = samples.columns[index] || null;
    const range = colourPoints(points, column);
    showLegend(column, range);
    state.objective = column ? column.name : null;
    state.colourRange = range;
  };
  select.addEventListener('change', () => choose(Number(select.value)));
  choose(0);
  // Tests pick a column by name: window.hapsynView.select(name) -> whether it exists.
  state.select = name => {
    const index = samples.columns.findIndex(c => c.name === name);
    if (index < 0) return false;
    select.value = String(index);
    choose(index);
    return true;
  };
  frameCamera(camera, controls, box);
  meshes.catch(e => { state.meshErrors.push(String(e)); state.meshesDone = true; });
  window.addEventListener('resize', () => {
    camera.aspect = container.clientWidth / container.clientHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(container.clientWidth, container.clientHeight);
  });
  // The virtual prototype (prototype.js) draws into the same scene.
  window.hapsynScene = { scene, size, mechanism: drawn, samples, renderer };
  window.dispatchEvent(new CustomEvent('hapsyn-scene', { detail: window.hapsynScene }));
  let frames = 0;
  renderer.setAnimationLoop(() => {
    controls.update();
    renderer.render(scene, camera);
    if (++frames === 2) state.ready = true;  // the first frame is on the canvas
  });
}

main().catch(e => {
  state.error = String(e && e.message ? e.message : e);
  document.getElementById('error').textContent = state.error;
});
