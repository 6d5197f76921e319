// A primitive fitted around a triangle mesh, so that a robot link given as a mesh keeps the fast
// capsule and sphere checks: a capsule that encloses every vertex (hence, being convex, the whole
// mesh), the smallest of a few candidate axes, and how far it overreaches.
#pragma once

#include "lazyboe/collision/mesh.h"
#include "lazyboe/robot/robot_model.h"

namespace lazyboe {

struct FittedShape {
  Shape shape;   // a capsule along the frame's z, or a sphere when its length would be 0
  Pose in_mesh;  // the shape's frame in the mesh's frame
  // The largest distance from a point of the shape's surface to the mesh, m: how much larger
  // than the link the fitted shape is at its worst (sampled over the surface).
  double over_approximation = 0;
};

// The enclosing capsule of least volume over the mesh's three principal axes: for each axis the
// axis line through the smallest enclosing circle of the projected vertices (Badoiu-Clarkson
// iterations), the least radius about it, and the shortest segment whose caps still enclose.
FittedShape fit_enclosing_capsule(const TriangleMesh& mesh);

// The mesh's extent along its thinnest principal direction, m: 0 for a flat (degenerate) mesh.
double thinnest_extent(const TriangleMesh& mesh);

// The largest distance from the sampled surface of `shape` (a capsule or sphere placed at
// `in_mesh`) to the mesh's triangles, m.
double largest_surface_gap(const TriangleMesh& mesh, const Shape& shape, const Pose& in_mesh);

}  // namespace lazyboe
