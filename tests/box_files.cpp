#include "box_files.h"

#include <octomap/OcTree.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <stdexcept>

#include "test_util.h"

namespace lazyboe::test {

TriangleMesh BoxFiles::mesh() const {
  TriangleMesh m;
  for (int k = 0; k < 8; ++k)
    m.vertices.emplace_back((k & 1 ? 0.5 : -0.5) * size.x(), (k & 2 ? 0.5 : -0.5) * size.y(),
                            (k & 4 ? 0.5 : -0.5) * size.z());
  const int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
                           {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  for (const auto& f : faces) {
    m.triangles.emplace_back(f[0], f[1], f[2]);
    m.triangles.emplace_back(f[0], f[2], f[3]);
  }
  return m;
}

std::vector<Eigen::Vector3d> BoxFiles::points() const {
  std::vector<Eigen::Vector3d> out;
  const double step = resolution / 2;
  const Eigen::Vector3i n = (size / step).array().round().cast<int>();
  for (int i = 0; i <= n.x(); ++i)
    for (int j = 0; j <= n.y(); ++j)
      for (int k = 0; k <= n.z(); ++k)
        out.push_back(centre - size / 2 + Eigen::Vector3d(i, j, k) * step);
  return out;
}

std::string BoxFiles::obj() const {
  const TriangleMesh m = mesh();
  std::string text;
  for (const Eigen::Vector3d& v : m.vertices)
    text += "v " + std::to_string(v.x()) + " " + std::to_string(v.y()) + " " +
            std::to_string(v.z()) + "\n";
  for (const Eigen::Vector3i& t : m.triangles)
    text += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
            std::to_string(t[2] + 1) + "\n";
  return write_temp_file(name + ".obj", text);
}

std::string BoxFiles::binary_stl() const {
  const TriangleMesh m = mesh();
  std::string bytes(80, ' ');
  auto put = [&](const void* p, size_t n) { bytes.append(static_cast<const char*>(p), n); };
  const uint32_t count = static_cast<uint32_t>(m.triangles.size());
  put(&count, 4);
  for (const Eigen::Vector3i& t : m.triangles) {
    const float normal[3] = {0, 0, 0};
    put(normal, sizeof normal);
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3f v = m.vertices[t[c]].cast<float>();
      put(v.data(), 12);
    }
    const uint16_t attributes = 0;
    put(&attributes, 2);
  }
  return write_temp_file(name + ".stl", bytes);
}

std::string BoxFiles::collada() const {
  const TriangleMesh m = mesh();
  std::string positions, indices;
  for (const Eigen::Vector3d& v : m.vertices)
    positions +=
        std::to_string(v.x()) + " " + std::to_string(v.y()) + " " + std::to_string(v.z()) + " ";
  for (const Eigen::Vector3i& t : m.triangles)
    indices += std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + " ";
  const std::string n = std::to_string(m.vertices.size()), t = std::to_string(m.triangles.size());
  return write_temp_file(name + ".dae", R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries><geometry id="box"><mesh>
    <source id="pos"><float_array id="pos-array" count=")" +
                                            std::to_string(3 * m.vertices.size()) + R"(">)" +
                                            positions + R"(</float_array>
      <technique_common><accessor source="#pos-array" count=")" +
                                            n + R"(" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="vtx"><input semantic="POSITION" source="#pos"/></vertices>
    <triangles count=")" + t + R"("><input semantic="VERTEX" source="#vtx" offset="0"/><p>)" +
                                            indices + R"(</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="scene"><node id="box-node">
    <instance_geometry url="#box"/></node></visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)");
}

std::string BoxFiles::ply(bool binary) const {
  const std::vector<Eigen::Vector3d> pts = points();
  std::string text = std::string("ply\nformat ") + (binary ? "binary_little_endian" : "ascii") +
                     " 1.0\nelement vertex " + std::to_string(pts.size()) +
                     "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  for (const Eigen::Vector3d& p : pts) {
    if (binary) {
      const Eigen::Vector3f f = p.cast<float>();
      text.append(reinterpret_cast<const char*>(f.data()), 12);
    } else {
      text +=
          std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
    }
  }
  return write_temp_file(name + (binary ? "-binary.ply" : ".ply"), text);
}

std::string BoxFiles::bt() const {
  const std::string path = write_temp_file(name + ".bt", "");
  if (!voxelise(points(), resolution, name)->writeBinaryConst(path))
    throw std::runtime_error("cannot write " + path);
  return path;
}

}  // namespace lazyboe::test
