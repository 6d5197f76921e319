#include "lazyboe/collision/convex_hull.h"

#include <Eigen/Geometry>
#include <cstdio>
#include <cstdlib>
#include <unordered_map>
#include <utility>
#include <vector>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

#include "lazyboe/common/error.h"

namespace lazyboe {
namespace {

// Qhull's state for one hull, freed however the call ends; its messages go to a memory buffer
// so that a failure can be told in one line.
class QhullRun {
 public:
  QhullRun() {
    messages_ = open_memstream(&text_, &size_);
    qh_zero(&qh_, messages_);
  }
  ~QhullRun() {
    qh_freeqhull(&qh_, !qh_ALL);
    int curlong = 0, totlong = 0;
    qh_memfreeshort(&qh_, &curlong, &totlong);
    if (messages_) std::fclose(messages_);
    std::free(text_);
  }
  QhullRun(const QhullRun&) = delete;
  QhullRun& operator=(const QhullRun&) = delete;

  // Qt: triangulated output (every facet a triangle).
  bool run(std::vector<coordT>& points) {
    char options[] = "qhull Qt";
    return qh_new_qhull(&qh_, 3, static_cast<int>(points.size() / 3), points.data(), False, options,
                        nullptr, messages_) == 0;
  }
  std::string first_message() {
    std::fflush(messages_);
    std::string text = text_ ? std::string(text_, size_) : "";
    const size_t end = text.find('\n', text.find_first_not_of("\n "));
    return text.substr(0, end);
  }
  qhT* qh() { return &qh_; }

 private:
  qhT qh_;
  FILE* messages_ = nullptr;
  char* text_ = nullptr;
  size_t size_ = 0;
};

}  // namespace

TriangleMesh convex_hull(const TriangleMesh& mesh, const std::string& where) {
  std::vector<coordT> points;
  points.reserve(3 * mesh.vertices.size());
  for (const Eigen::Vector3d& v : mesh.vertices) points.insert(points.end(), {v.x(), v.y(), v.z()});
  if (mesh.vertices.size() < 4) fail(where, "a convex hull needs at least 4 vertices");
  QhullRun run;
  if (!run.run(points)) fail(where, "no convex hull (Qhull: " + run.first_message() + ")");
  qhT* qh = run.qh();
  TriangleMesh hull;
  std::unordered_map<int, int> index;  // mesh vertex -> hull vertex
  auto hull_vertex = [&](vertexT* vertex) {
    const int id = qh_pointid(qh, vertex->point);
    const auto [it, added] = index.emplace(id, static_cast<int>(hull.vertices.size()));
    if (added) hull.vertices.push_back(mesh.vertices[id]);
    return it->second;
  };
  facetT* facet;
  FORALLfacets {
    int corner[3], k = 0;
    vertexT *vertex, **vertexp;
    FOREACHvertex_(facet->vertices) {
      if (k < 3) corner[k] = hull_vertex(vertex);
      ++k;
    }
    if (k != 3) fail(where, "Qhull returned a facet that is not a triangle");
    // Outward: the triangle's normal along Qhull's facet normal.
    const Eigen::Vector3d& a = hull.vertices[corner[0]];
    const Eigen::Vector3d normal =
        (hull.vertices[corner[1]] - a).cross(hull.vertices[corner[2]] - a);
    if (normal.dot(Eigen::Vector3d(facet->normal[0], facet->normal[1], facet->normal[2])) < 0)
      std::swap(corner[1], corner[2]);
    hull.triangles.emplace_back(corner[0], corner[1], corner[2]);
  }
  return hull;
}

}  // namespace lazyboe
