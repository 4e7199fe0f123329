#!/usr/bin/env python3
"""Writes the small example meshes of share/serial_chain/phantom_3r_meshes.urdf (drawn by
`hapsyn view`): binary STL cylinders and a unit box, and one COLLADA cube. Simple shapes, a few kB
each; deterministic (running it again gives the same bytes).

Usage: make-example-meshes.py [OUT_DIR] (default share/serial_chain/meshes/phantom_3r).
"""
import math
import os
import struct
import sys


def binary_stl(triangles, name):
    """Binary STL: 80-byte header, count, then normal + 3 vertices + 2 attribute bytes each."""
    out = bytearray(name.encode()[:80].ljust(80, b" "))
    out += struct.pack("<I", len(triangles))
    for a, b, c in triangles:
        u = [b[k] - a[k] for k in range(3)]
        v = [c[k] - a[k] for k in range(3)]
        n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        length = math.sqrt(sum(x * x for x in n)) or 1.0
        out += struct.pack("<12fH", *[x / length for x in n], *a, *b, *c, 0)
    return bytes(out)


def cylinder(radius, height, segments=24):
    """A closed cylinder along z from 0 to height, outward-facing triangles."""
    ring = [(radius * math.cos(2 * math.pi * k / segments), radius * math.sin(2 * math.pi * k / segments))
            for k in range(segments)]
    tris = []
    for k in range(segments):
        (x0, y0), (x1, y1) = ring[k], ring[(k + 1) % segments]
        tris += [((x0, y0, 0), (x1, y1, 0), (x1, y1, height)), ((x0, y0, 0), (x1, y1, height), (x0, y0, height)),
                 ((0, 0, 0), (x1, y1, 0), (x0, y0, 0)), ((0, 0, height), (x0, y0, height), (x1, y1, height))]
    return tris


CUBE_CORNERS = [(x, y, z) for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
# The six faces as corner indices (counter-clockwise seen from outside), two triangles each.
CUBE_FACES = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]


def unit_box():
    """A 1 x 1 x 1 box centred at the origin."""
    tris = []
    for a, b, c, d in CUBE_FACES:
        p = [CUBE_CORNERS[i] for i in (a, b, c, d)]
        tris += [(p[0], p[1], p[2]), (p[0], p[2], p[3])]
    return tris


def collada_cube(side):
    """A COLLADA 1.4.1 cube of edge `side` [m], centred at the origin, Z up, one material."""
    positions = " ".join(f"{c * side:g}" for corner in CUBE_CORNERS for c in corner)
    indices = " ".join(f"{i}" for a, b, c, d in CUBE_FACES for i in (a, b, c, a, c, d))
    return f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_effects>
    <effect id="grey-effect"><profile_COMMON><technique sid="common"><phong>
      <diffuse><color>0.35 0.55 0.75 1</color></diffuse>
    </phong></technique></profile_COMMON></effect>
  </library_effects>
  <library_materials><material id="grey" name="grey"><instance_effect url="#grey-effect"/></material></library_materials>
  <library_geometries>
    <geometry id="cube" name="cube"><mesh>
      <source id="cube-positions">
        <float_array id="cube-positions-array" count="24">{positions}</float_array>
        <technique_common><accessor source="#cube-positions-array" count="8" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common>
      </source>
      <vertices id="cube-vertices"><input semantic="POSITION" source="#cube-positions"/></vertices>
      <triangles material="grey" count="12">
        <input semantic="VERTEX" source="#cube-vertices" offset="0"/>
        <p>{indices}</p>
      </triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene"><node id="cube-node" name="cube">
      <instance_geometry url="#cube"><bind_material><technique_common>
        <instance_material symbol="grey" target="#grey"/>
      </technique_common></bind_material></instance_geometry>
    </node></visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
"""


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "share", "serial_chain",
                                                             "meshes", "phantom_3r")
    os.makedirs(out, exist_ok=True)
    files = {"base.stl": binary_stl(cylinder(0.06, 0.05), "hapsyn example: base, cylinder r 0.06 h 0.05"),
             "turret.stl": binary_stl(cylinder(0.035, 0.1), "hapsyn example: turret, cylinder r 0.035 h 0.1"),
             "rod.stl": binary_stl(cylinder(0.008, 1.0, 16), "hapsyn example: rod, cylinder r 0.008 h 1"),
             "unit_box.stl": binary_stl(unit_box(), "hapsyn example: unit box")}
    for name, data in files.items():
        with open(os.path.join(out, name), "wb") as f:
            f.write(data)
    with open(os.path.join(out, "gimbal.dae"), "w") as f:
        f.write(collada_cube(0.03))
    print(f"wrote {len(files) + 1} meshes to {out}")


if __name__ == "__main__":
    main()
