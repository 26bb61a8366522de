#!/usr/bin/env python3
"""Writes the example meshes of scenes/meshes/ (used by scenes/pipe_mesh_3d.yaml and by
tests/unit/test_structure_scenes.cpp). Standard library only; run it from anywhere:

    python3 scenes/meshes/make_meshes.py

pipe.stl   binary STL, closed circular cylinder, radius 0.05 m, length 0.4 m, axis along z, centred at
           the origin; 128 sides, caps fanned from their centres (512 triangles, 26 kB).
ball.obj   OBJ, closed sphere of radius 0.05 m about the origin: a geodesic sphere (an icosahedron with
           a vertex at each pole, each face split into 17 x 17 triangles, the vertices on the sphere;
           5780 triangles, 2892 vertices, under 200 kB). No vertex lies on the plane z = 0, which
           cuts it (2D scenes) into a polygon close to a circle.
block.ply  ASCII PLY, box 0.2 x 0.1 x 0.05 m centred at the origin, six quad faces.

All faces are counter-clockwise seen from outside (outward normals), as turbid requires. The script
prints each mesh's area and volume next to the analytic values of the smooth shape; the curved
meshes are within 0.2 % of them (asserted here), so that the sampled values can be held to 1 %.
"""
import math
import os
import struct

R = 0.05        # pipe and ball radius [m]
L_PIPE = 0.4    # pipe length [m]
PIPE_SIDES = 128
BALL_FREQUENCY = 17  # 20 * 17^2 = 5780 triangles: within 0.2 % and under 200 kB
BLOCK = (0.2, 0.1, 0.05)

HERE = os.path.dirname(os.path.abspath(__file__))


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def area_volume(vertices, triangles):
    area = volume = 0.0
    for i, j, k in triangles:
        a, b, c = vertices[i], vertices[j], vertices[k]
        n = cross(sub(b, a), sub(c, a))
        area += 0.5 * math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
        volume += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                   + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0
    return area, volume


def pipe():
    v, t = [], []
    n = PIPE_SIDES
    for z in (-0.5 * L_PIPE, 0.5 * L_PIPE):
        for j in range(n):
            phi = 2 * math.pi * j / n
            v.append((R * math.cos(phi), R * math.sin(phi), z))
    bottom_c, top_c = len(v), len(v) + 1
    v += [(0.0, 0.0, -0.5 * L_PIPE), (0.0, 0.0, 0.5 * L_PIPE)]
    for j in range(n):
        a, b = j, (j + 1) % n
        t.append((a, b, n + b))       # side
        t.append((a, n + b, n + a))
        t.append((top_c, n + a, n + b))  # top cap, normal +z
        t.append((bottom_c, b, a))       # bottom cap, normal -z
    return v, t


def ball():
    """Geodesic sphere: every face of an icosahedron (a vertex at each pole) is split into
    BALL_FREQUENCY^2 triangles on a uniform grid whose points are pushed out onto the sphere."""
    nu = BALL_FREQUENCY
    a = math.atan(0.5)  # latitude of the icosahedron's two rings of five vertices
    ico = [(0.0, 0.0, 1.0)]
    ico += [(math.cos(a) * math.cos(2 * math.pi * k / 5), math.cos(a) * math.sin(2 * math.pi * k / 5), math.sin(a))
            for k in range(5)]
    ico += [(math.cos(a) * math.cos(2 * math.pi * (k + 0.5) / 5), math.cos(a) * math.sin(2 * math.pi * (k + 0.5) / 5),
             -math.sin(a)) for k in range(5)]
    ico.append((0.0, 0.0, -1.0))
    faces = []
    for k in range(5):
        u, u1, l, l1 = 1 + k, 1 + (k + 1) % 5, 6 + k, 6 + (k + 1) % 5
        faces += [(0, u, u1), (u, l, u1), (u1, l, l1), (11, l1, l)]
    v, index, t = [], {}, []

    def vertex(p):
        n = math.sqrt(p[0] ** 2 + p[1] ** 2 + p[2] ** 2)
        key = tuple(round(x / n, 12) + 0.0 for x in p)  # grid points shared by two faces merge
        if key not in index:
            index[key] = len(v)
            v.append(tuple(R * x / n for x in p))
        return index[key]

    for fa, fb, fc in faces:
        A, B, C = ico[fa], ico[fb], ico[fc]
        if sum(x * y for x, y in zip(cross(sub(B, A), sub(C, A)), A)) < 0:  # make it face outward
            B, C = C, B
        g = {}
        for i in range(nu + 1):
            for j in range(nu + 1 - i):
                w = (nu - i - j) / nu
                g[i, j] = vertex(tuple(w * A[k] + i / nu * B[k] + j / nu * C[k] for k in range(3)))
        for i in range(nu):
            for j in range(nu - i):
                t.append((g[i, j], g[i + 1, j], g[i, j + 1]))
                if i + j < nu - 1:
                    t.append((g[i + 1, j], g[i + 1, j + 1], g[i, j + 1]))
    return v, t


def write_binary_stl(path, v, t):
    with open(path, "wb") as f:
        f.write(b"turbid scenes/meshes/make_meshes.py: closed cylinder R 0.05 m L 0.4 m".ljust(80, b" "))
        f.write(struct.pack("<I", len(t)))
        for tri in t:
            a, b, c = (v[k] for k in tri)
            n = cross(sub(b, a), sub(c, a))
            ln = math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2)
            f.write(struct.pack("<12fH", *(x / ln for x in n), *a, *b, *c, 0))


def write_obj(path, v, t):
    with open(path, "w") as f:
        f.write("# turbid scenes/meshes/make_meshes.py: geodesic sphere R = 0.05 m, frequency %d\no ball\n"
                % BALL_FREQUENCY)
        for p in v:
            f.write("v %.7g %.7g %.7g\n" % p)
        for a, b, c in t:
            f.write("f %d %d %d\n" % (a + 1, b + 1, c + 1))


def write_ply_box(path, size):
    a, b, c = size
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\ncomment turbid scenes/meshes/make_meshes.py: box %g x %g x %g m\n"
                "element vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
                "element face 6\nproperty list uchar int vertex_indices\nend_header\n" % size)
        for k in range(8):
            f.write("%.9g %.9g %.9g\n" % ((0.5 if k & 1 else -0.5) * a, (0.5 if k & 2 else -0.5) * b,
                                          (0.5 if k & 4 else -0.5) * c))
        # counter-clockwise seen from outside: -z, +z, -y, +y, -x, +x
        f.write("4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n")


def report(name, v, t, area_ref, volume_ref, limit):
    area, volume = area_volume(v, t)
    ea, ev = area / area_ref - 1, volume / volume_ref - 1
    print("%-9s %5d vertices %5d triangles  area %.6e (%+.3f %%)  volume %.6e (%+.3f %%)"
          % (name, len(v), len(t), area, 100 * ea, volume, 100 * ev))
    assert abs(ea) < limit and abs(ev) < limit, name


def main():
    v, t = pipe()
    report("pipe.stl", v, t, 2 * math.pi * R * L_PIPE + 2 * math.pi * R * R, math.pi * R * R * L_PIPE, 0.002)
    write_binary_stl(os.path.join(HERE, "pipe.stl"), v, t)
    v, t = ball()
    report("ball.obj", v, t, 4 * math.pi * R * R, 4.0 / 3.0 * math.pi * R ** 3, 0.002)
    write_obj(os.path.join(HERE, "ball.obj"), v, t)
    a, b, c = BLOCK
    write_ply_box(os.path.join(HERE, "block.ply"), BLOCK)
    print("block.ply     8 vertices     6 quads      area %.6e           volume %.6e"
          % (2 * (a * b + b * c + c * a), a * b * c))


if __name__ == "__main__":
    main()
