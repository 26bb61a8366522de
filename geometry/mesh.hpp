// Structures from triangle meshes (STL, OBJ, PLY and the other formats assimp reads), sampled into
// boundary particles like the primitives of primitives.hpp. No physics, no logging; every defect is a
// MeshError (a std::runtime_error) whose what() is a complete sentence for the user.
//
// Loading (load_mesh). The file is read with assimp (triangulating polygons and joining identical
// vertices, nothing else: no normal fixing, no removal of degenerate or duplicate faces). All meshes
// of the scene are merged into one, each vertex moved by the product of the node transforms above it
// (a mirroring transform reverses the winding of its triangles so that they keep facing outward).
// Points and lines are ignored (they have no area). Vertices closer than 1e-9 times the bounding-box
// diagonal are then merged (STL stores every triangle's corners separately) and triangles left with a
// repeated vertex dropped (they have no area). The result must be a closed, consistently oriented,
// outward-facing surface; the checks, in this order, and the MeshError they raise:
//   not found      the file does not exist ("... was not found.", checked before assimp)
//   unreadable     assimp cannot read it: unknown format or corrupt ("... could not be read: <assimp's
//                  reason>.")
//   empty          a 0-byte file, or a scene without triangles ("... is empty ...")
//   open           an edge used by only one triangle ("... is open: N boundary edges, e.g. the edge from
//                  (x, y, z) to (x, y, z) ...")
//   non-manifold   an edge used by more than two triangles ("... is non-manifold: ...")
//   orientation    an edge traversed twice in the same direction ("... has an inconsistent orientation:
//                  ...")
//   inside-out     signed volume < 0 ("... is inside-out: its normals point inward ...; flip the faces.")
//   flat           signed volume ~ 0 ("... encloses no volume ...")
// Coordinates in the messages are those of the file (after the node transforms).
//
// Sampling (sample_mesh). The placement (placement.hpp: scale, rotation about x, y, z, translation)
// is applied to the vertices first.
//  3D: particles sit on a cell-centred cubic lattice of spacing dx whose origin is the minimum corner
//   of the placed mesh's bounding box: points origin + (i + 0.5, j + 0.5, k + 0.5) dx. The lattice is
//   thus tied to the body, not to the world origin (a translated body gives translated particles), and
//   a face that is a bounding-box face lies dx/2 from the first particle row. A lattice point is kept
//   when it lies inside the mesh and its depth (distance to the nearest triangle) is < layers * dx
//   (layers <= 0: the whole solid). Inside means a non-zero winding number along the line through the
//   point parallel to x: the signed crossings of that line with the triangles (projected to the
//   (y, z) plane, with edge tests evaluated identically for the two triangles sharing an edge and a
//   symbolic perturbation of the line for exact hits on edges and vertices) are summed up to the point,
//   so the test is exact up to rounding of the crossing abscissae even for points next to the surface.
//   For each particle: depth = distance to the nearest point c of the mesh; normal = (c - x) / depth,
//   which is the outward face normal when c lies inside a face and a direction of the normal cone at
//   an edge or vertex otherwise (a point on the surface, depth ~ 0, takes the angle-weighted
//   pseudo-normal of the nearest face, edge or vertex), so x + depth * normal = c is on the mesh;
//   layer = int(depth / dx).
//   Volumes: the volume of each lattice cell inside the mesh is integrated along 8 x 8 lines parallel
//   to x per cell (the inside length of each line within the cell is exact, from the sorted
//   crossings; a midpoint rule across the lines). A particle's volume is its own cell's inside volume
//   plus that of every cell whose centre lies outside the mesh but which is partly inside, given to the
//   nearest kept particle, so with layers <= 0 the volumes sum to the sampled volume of the mesh.
//   SampledBody::volume is the sampled volume of the whole solid (the sum over all cells) also when
//   layers limits the particles to a shell: it is the body's volume, not the shell's (unlike the
//   primitives, whose volume is that of the sampled layers).
//   Surface: every triangle is split into sub-triangles of edges < dx/2; each sub-triangle's area goes
//   to the layer-0 particle nearest to its centroid (surface_share); surface_area is their sum, i.e.
//   the area of the placed mesh.
//  2D (dims == 2): the placed mesh is cut by the plane z = 0 (vertices on the plane count as above
//   it); the crossing segments are chained into closed polygons (outer boundaries counter-clockwise),
//   and the enclosed area is sampled the same way on a square lattice (origin at the minimum corner of
//   the polygons' bounding box, 8 lines per cell row): depth = distance to the nearest segment,
//   normal its outward normal in the plane, volumes = cell areas inside [m^2], surface_area = the
//   perimeter [m], all points at z = 0. In 2D any rotation and translation[2] are allowed: they choose
//   which section of the mesh the plane cuts. A cut that misses the mesh is a MeshError ("the plane
//   z = 0 does not cut the mesh").
// A mesh so thin that no lattice point lies inside it is a MeshError; bad arguments (dx, dims, scale)
// are std::invalid_argument.
//
// Cost: O(triangles + cells of the bounding box) memory (about 13 bytes per lattice cell). Single
// thread, Release: a sphere of 20k triangles sampled into 100k particles takes about 1 s filled
// (a sphere is the worst case for the nearest-triangle search: its centre is equidistant from all
// triangles), 0.2 s with 3 layers; its 2D section into 200k particles 0.1 s.
// The exact signed distance to a (placed) mesh solid, with the same inside test, is geometry/solid.hpp;
// the internals both use (BVH, closest points, crossings, the section by z = 0) are mesh_detail.hpp.
#pragma once
#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include "geometry/placement.hpp"
#include "geometry/primitives.hpp"
#include "geometry/shapes.hpp"

namespace turbid::geometry {

struct TriangleMesh {
  std::vector<Point> vertices;
  std::vector<std::array<int, 3>> triangles;  // vertex indices, counter-clockwise seen from outside

  double area() const;    // sum of the triangle areas
  double volume() const;  // signed enclosed volume by the divergence theorem (> 0 for outward faces)
};

class MeshError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads a mesh file (see above); throws MeshError for a missing, unreadable, empty, open,
// non-manifold, inconsistently oriented, inside-out or flat mesh.
TriangleMesh load_mesh(const std::string& path);

// The closedness / orientation checks of load_mesh on a mesh built in code. `subject` names the mesh
// in the messages ("mesh file 'hull.stl'", "the mesh"). Throws MeshError.
void validate_mesh(const TriangleMesh& mesh, const std::string& subject);

// Boundary particles of the solid bounded by `mesh` (validated first: MeshError) at spacing dx;
// layers <= 0 fills the solid; dims 2 samples the section by the plane z = 0. See above.
SampledBody sample_mesh(const TriangleMesh& mesh, double dx, int layers, int dims, const Placement& placement = {});

}  // namespace turbid::geometry
