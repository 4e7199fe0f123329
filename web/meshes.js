// A mechanism's meshes in the 3D view (the study's "meshes": a URDF's STL and COLLADA visuals,
// hapsyn/mesh_drawing.hpp). Each file is fetched once from its route ("/api/mesh/K") and parsed
// once by three's STLLoader or ColladaLoader; every visual that uses it is placed at its pose (the
// mesh frame in the scene frame) and scale. A COLLADA file's <unit> applies, its <up_axis> does
// not: its coordinates are taken as written in the link frame (z up, as URDF viewers such as rviz
// do). With meshes, the capsules fade, and a check box in the panel shows or hides them.
import * as THREE from 'three';
// Bare names of the page's import map, so that a report's data: copy of this module resolves them.
import { STLLoader } from 'three/addons/loaders/STLLoader.js';
import { ColladaLoader } from 'three/addons/loaders/ColladaLoader.js';

const MESH_COLOUR = 0x8fa3b8;

async function fetchFile(route, format) {
  // A report (hapsyn report) carries the files in the page, base64 encoded.
  const inline = document.querySelector(`script[type="application/octet-stream"][data-route="${route}"]`);
  if (inline) {
    const bytes = Uint8Array.from(atob(inline.textContent), c => c.charCodeAt(0));
    return format === 'dae' ? new TextDecoder().decode(bytes) : bytes.buffer;
  }
  const response = await fetch(route);
  if (!response.ok) throw new Error(`${route}: HTTP ${response.status}`);
  return format === 'dae' ? response.text() : response.arrayBuffer();
}

// The parsed file: a function that makes one more object of it.
function parser(format, data, route) {
  if (format === 'stl') {
    const geometry = new STLLoader().parse(data);
    const material = new THREE.MeshStandardMaterial({ color: MESH_COLOUR, metalness: 0.2, roughness: 0.55 });
    return () => new THREE.Mesh(geometry, material);
  }
  if (format === 'dae') {
    const collada = new ColladaLoader().parse(data, route);
    if (!collada || !collada.scene) throw new Error(`${route}: not a COLLADA file three can read`);
    collada.scene.rotation.set(0, 0, 0);  // the up axis ignored (see the file comment); the unit kept
    // A file without normals would be drawn black under the lights.
    collada.scene.traverse(o => {
      if (o.isMesh && !o.geometry.getAttribute('normal')) o.geometry.computeVertexNormals();
    });
    return () => collada.scene.clone();
  }
  throw new Error(`${route}: format "${format}" is not drawn`);
}

function place(make, mesh) {
  const holder = new THREE.Group();
  holder.matrixAutoUpdate = false;
  holder.matrix.set(...mesh.pose.flat());
  holder.name = mesh.link;
  const object = make();
  object.scale.multiply(new THREE.Vector3(...mesh.scale));
  holder.add(object);
  return holder;
}

// A check box in the panel that shows or hides the capsules.
function capsuleToggle(capsules) {
  const label = document.createElement('label');
  label.id = 'capsules-toggle';
  const box = document.createElement('input');
  box.type = 'checkbox';
  box.checked = true;
  box.addEventListener('change', () => { capsules.visible = box.checked; });
  label.append(box, ' capsules (the kinematic links) over the meshes');
  const panel = document.getElementById('panel');
  panel.insertBefore(label, document.getElementById('error'));
}

function fade(capsules) {
  capsules.traverse(o => {
    if (!o.material) return;
    o.material = o.material.clone();
    o.material.transparent = true;
    o.material.opacity = 0.35;
  });
}

// The box a placed mesh takes in the scene frame, for tests: {link, min, max}.
function boxOf(holder) {
  holder.updateMatrixWorld(true);
  const box = new THREE.Box3().setFromObject(holder);
  return { link: holder.name, min: box.min.toArray(), max: box.max.toArray() };
}

/// Adds the study's meshes to `scene`. Sets state.meshes (how many were placed), state.meshBoxes
/// (the axis-aligned box each takes in the scene frame, in the study's order), state.meshErrors
/// (one message per file that failed) and state.meshesDone (true when every file was tried).
export async function addMeshes(scene, study, capsules, state) {
  const meshes = study.meshes || [];
  state.meshes = 0;
  state.meshBoxes = [];
  state.meshErrors = [];
  state.meshesDone = false;
  if (meshes.length > 0) {
    fade(capsules);
    capsuleToggle(capsules);
  }
  const group = new THREE.Group();
  group.name = 'meshes';
  scene.add(group);
  const parsed = new Map();  // route -> maker, or null when it failed
  for (const mesh of meshes) {
    if (!parsed.has(mesh.route)) {
      try {
        parsed.set(mesh.route, parser(mesh.format, await fetchFile(mesh.route, mesh.format), mesh.route));
      } catch (e) {
        parsed.set(mesh.route, null);
        state.meshErrors.push(String(e && e.message ? e.message : e));
      }
    }
    const make = parsed.get(mesh.route);
    if (!make) continue;
    const holder = place(make, mesh);
    group.add(holder);
    state.meshBoxes.push(boxOf(holder));
    state.meshes += 1;
  }
  state.meshesDone = true;
  return group;
}
