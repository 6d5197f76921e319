// The convex hull of a mesh (Qhull, Debian's libqhull-dev), for the `convex` representation of
// a robot link's collision mesh: one convex shape that GJK checks as fast as a primitive, exact
// for a convex part and never less conservative than the mesh (it encloses every vertex).
#pragma once

#include <string>

#include "lazyboe/collision/mesh.h"

namespace lazyboe {

// The hull's vertices (a subset of the mesh's) and its faces as outward-facing triangles, a
// closed surface. Throws Error(`where`: ...) when Qhull cannot make one (fewer than four
// vertices, or all in one plane).
TriangleMesh convex_hull(const TriangleMesh& mesh, const std::string& where);

}  // namespace lazyboe
