// The human of a scene that models one (/api/study "figure"): the arm through its joints at the
// drawn sample, the torso outline and the head, in skin and cloth colours so that they read
// apart from the mechanism's capsules.
import * as THREE from 'three';

// A polyline of capsules (cylinders between points, spheres at the points).
function tube(points, radius, material) {
  const group = new THREE.Group();
  const up = new THREE.Vector3(0, 1, 0);
  const at = points.map(p => new THREE.Vector3(p[0], p[1], p[2]));
  at.forEach((p, i) => {
    const joint = new THREE.Mesh(new THREE.SphereGeometry(radius, 16, 12), material);
    joint.position.copy(p);
    group.add(joint);
    if (i === 0) return;
    const along = new THREE.Vector3().subVectors(p, at[i - 1]);
    const length = along.length();
    if (length === 0) return;
    const link = new THREE.Mesh(new THREE.CylinderGeometry(radius, radius, length, 16), material);
    link.position.addVectors(p, at[i - 1]).multiplyScalar(0.5);
    link.quaternion.setFromUnitVectors(up, along.divideScalar(length));
    group.add(link);
  });
  return group;
}

// The figure as a three.js group, or null when the study has none.
export function humanFigure(figure) {
  if (!figure) return null;
  const group = new THREE.Group();
  group.name = 'human';
  const skin = new THREE.MeshStandardMaterial({ color: 0xd9a47f, roughness: 0.8 });
  const cloth = new THREE.MeshStandardMaterial({ color: 0x6b7fa3, roughness: 0.9, transparent: true, opacity: 0.55 });
  group.add(tube(figure.arm, 0.025, skin));
  for (const line of figure.body_lines) group.add(tube(line, 0.04, cloth));
  const head = new THREE.Mesh(new THREE.SphereGeometry(figure.head_radius, 24, 16), skin);
  head.position.set(...figure.head_centre);
  group.add(head);
  return group;
}

// Every point of the figure, for framing the camera.
export function figurePoints(figure) {
  if (!figure) return [];
  const c = figure.head_centre, r = figure.head_radius;
  return [...figure.arm, ...figure.body_lines.flat(), [c[0], c[1], c[2] + r]];
}
