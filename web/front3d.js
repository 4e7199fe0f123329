// The 3D scatter of a front of three or more objectives (front.js): three chosen objectives,
// each scaled to its range, in a unit cube; drag to turn it, click a point to pick it. Imports
// only 'three' (a bare name), so that it also runs as a data: module of `hapsyn report`.
import * as THREE from 'three';

const COLOUR = 0x3b528b, SELECTED = 0xc8553d;

function scaled(values) {
  const finite = values.filter(v => v !== null && Number.isFinite(v));
  const lo = Math.min(...finite), hi = Math.max(...finite);
  return values.map(v => (v === null || !Number.isFinite(v) ? NaN : hi > lo ? (v - lo) / (hi - lo) - 0.5 : 0));
}

/// A 3D scatter in `container` (width x height pixels). Returns {draw(xs, ys, zs), select(i),
/// position(i) -> [clientX, clientY, depth], dispose()}; onPick(i) on a click on point i.
export function scatter3d(container, width, height, onPick) {
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio);
  renderer.setSize(width, height);
  container.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xffffff);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x888888, 2.5));
  const camera = new THREE.PerspectiveCamera(40, width / height, 0.01, 20);
  camera.up.set(0, 0, 1);
  camera.position.set(1.5, -1.9, 1.2);
  camera.lookAt(0, 0, 0);
  const group = new THREE.Group();
  scene.add(group);
  const box = new THREE.LineSegments(new THREE.EdgesGeometry(new THREE.BoxGeometry(1, 1, 1)),
                                     new THREE.LineBasicMaterial({ color: 0x999999 }));
  group.add(box);
  // The three axes from the cube's low corner: x red, y green, z blue (as the scene frame).
  for (const [direction, colour] of [[[1, 0, 0], 0xd62728], [[0, 1, 0], 0x2ca02c], [[0, 0, 1], 0x1f4e9c]]) {
    group.add(new THREE.ArrowHelper(new THREE.Vector3(...direction), new THREE.Vector3(-0.5, -0.5, -0.5), 1.1, colour, 0.06, 0.03));
  }
  const geometry = new THREE.SphereGeometry(0.025, 12, 8);
  let spheres = [];
  const render = () => renderer.render(scene, camera);

  const draw = (xs, ys, zs) => {
    for (const s of spheres) group.remove(s);
    const [sx, sy, sz] = [scaled(xs), scaled(ys), scaled(zs)];
    spheres = sx.map((x, i) => {
      const s = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({ color: COLOUR }));
      s.position.set(x, sy[i], sz[i]);
      s.visible = Number.isFinite(x) && Number.isFinite(sy[i]) && Number.isFinite(sz[i]);
      s.userData.index = i;
      group.add(s);
      return s;
    });
    render();
  };
  const select = index => {
    spheres.forEach((s, i) => s.material.color.setHex(i === index ? SELECTED : COLOUR));
    render();
  };
  const position = index => {
    group.updateMatrixWorld();
    const p = spheres[index].getWorldPosition(new THREE.Vector3());
    const depth = p.distanceTo(camera.position);
    p.project(camera);
    const rect = renderer.domElement.getBoundingClientRect();
    return [rect.left + (p.x + 1) / 2 * rect.width, rect.top + (1 - p.y) / 2 * rect.height, depth];
  };

  // Drag turns the cube; a click (little movement) picks the nearest point under the pointer.
  let down = null;
  const canvas = renderer.domElement;
  canvas.addEventListener('pointerdown', e => { down = { x: e.clientX, y: e.clientY, moved: 0 }; });
  canvas.addEventListener('pointermove', e => {
    if (!down || !e.buttons) return;
    group.rotation.z += e.movementX * 0.01;
    group.rotation.x += e.movementY * 0.01;
    down.moved += Math.abs(e.movementX) + Math.abs(e.movementY);
    render();
  });
  canvas.addEventListener('pointerup', e => {
    const click = down && down.moved < 4;
    down = null;
    if (!click) return;
    const rect = canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2((e.clientX - rect.left) / rect.width * 2 - 1, -(e.clientY - rect.top) / rect.height * 2 + 1);
    const ray = new THREE.Raycaster();
    ray.setFromCamera(ndc, camera);
    const hit = ray.intersectObjects(spheres.filter(s => s.visible), false)[0];
    if (hit) onPick(hit.object.userData.index);
  });
  return { draw, select, position, canvas };
}
