#include "lazyboe/collision/mesh_fit.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "lazyboe/collision/fcl_shapes.h"

namespace lazyboe {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Principal {
  Eigen::Vector3d centroid;
  Eigen::Matrix3d axes;  // columns: principal directions, thinnest first
};

Principal principal_axes(const std::vector<Eigen::Vector3d>& points) {
  Principal p;
  p.centroid.setZero();
  for (const Eigen::Vector3d& v : points) p.centroid += v;
  p.centroid /= static_cast<double>(points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& v : points) cov += (v - p.centroid) * (v - p.centroid).transpose();
  p.axes = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors();
  return p;
}

// Centre of a small enclosing circle of 2-D points: Badoiu and Clarkson's iterations (each step
// moves the centre 1/(k+1) of the way to the farthest point), keeping the best centre seen.
Eigen::Vector2d enclosing_circle_centre(const std::vector<Eigen::Vector2d>& points) {
  Eigen::Vector2d lower = points.front(), upper = points.front();
  for (const Eigen::Vector2d& p : points) {
    lower = lower.cwiseMin(p);
    upper = upper.cwiseMax(p);
  }
  Eigen::Vector2d centre = (lower + upper) / 2, best = centre;
  double best_radius = std::numeric_limits<double>::infinity();
  for (int k = 1; k <= 200; ++k) {
    size_t far = 0;
    double far2 = -1;
    for (size_t i = 0; i < points.size(); ++i) {
      const double d2 = (points[i] - centre).squaredNorm();
      if (d2 > far2) far2 = d2, far = i;
    }
    if (far2 < best_radius) best_radius = far2, best = centre;
    centre += (points[far] - centre) / (k + 1);
  }
  return best;
}

struct Candidate {
  Shape shape;
  Pose in_mesh;
  double volume = std::numeric_limits<double>::infinity();
};

// The enclosing capsule along `axis` (unit), through the centroid's neighbourhood.
Candidate capsule_along(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& origin,
                        const Eigen::Vector3d& axis) {
  const Eigen::Vector3d u = axis.unitOrthogonal(), v = axis.cross(u);
  std::vector<Eigen::Vector2d> across(points.size());
  for (size_t i = 0; i < points.size(); ++i)
    across[i] = Eigen::Vector2d(u.dot(points[i] - origin), v.dot(points[i] - origin));
  const Eigen::Vector2d c = enclosing_circle_centre(across);
  double r2 = 0;
  for (const Eigen::Vector2d& p : across) r2 = std::max(r2, (p - c).squaredNorm());
  // Round up a little so that every vertex stays inside despite rounding.
  const double radius = std::sqrt(r2) * (1 + 1e-9) + 1e-12;
  // The segment [bottom, top] along the axis: a vertex beyond an end must lie in that end's cap.
  double top = -std::numeric_limits<double>::infinity(), bottom = -top;
  for (size_t i = 0; i < points.size(); ++i) {
    const double t = axis.dot(points[i] - origin);
    const double reach = std::sqrt(std::max(0.0, radius * radius - (across[i] - c).squaredNorm()));
    top = std::max(top, t - reach);
    bottom = std::min(bottom, t + reach);
  }
  const double length = std::max(0.0, top - bottom);
  Candidate k;
  k.shape.type = length > 0 ? ShapeType::Capsule : ShapeType::Sphere;
  k.shape.radius = radius;
  k.shape.length = length;
  k.in_mesh.R.col(0) = u;
  k.in_mesh.R.col(1) = v;
  k.in_mesh.R.col(2) = axis;
  k.in_mesh.p = origin + c.x() * u + c.y() * v + (top + bottom) / 2 * axis;
  k.volume = kPi * radius * radius * length + 4.0 / 3.0 * kPi * radius * radius * radius;
  return k;
}

// Points on the capsule's (or sphere's) surface: rings along the cylinder and over each cap.
std::vector<Eigen::Vector3d> surface_samples(const Shape& shape, const Pose& pose) {
  const int around = 24, along = 8, latitudes = 6;
  const double r = shape.radius, half = shape.type == ShapeType::Capsule ? shape.length / 2 : 0;
  std::vector<Eigen::Vector3d> points;
  auto ring = [&](double z, double ring_radius) {
    for (int k = 0; k < around; ++k) {
      const double a = 2 * kPi * k / around;
      points.push_back(pose *
                       Eigen::Vector3d(ring_radius * std::cos(a), ring_radius * std::sin(a), z));
    }
  };
  for (int s = 0; s <= along; ++s) ring(-half + 2 * half * s / along, r);
  for (int l = 1; l < latitudes; ++l) {
    const double phi = kPi / 2 * l / latitudes;  // above the cap's equator
    ring(half + r * std::sin(phi), r * std::cos(phi));
    ring(-half - r * std::sin(phi), r * std::cos(phi));
  }
  points.push_back(pose * Eigen::Vector3d(0, 0, half + r));
  points.push_back(pose * Eigen::Vector3d(0, 0, -half - r));
  return points;
}

}  // namespace

FittedShape fit_enclosing_capsule(const TriangleMesh& mesh) {
  const Principal principal = principal_axes(mesh.vertices);
  Candidate best;
  for (int a = 0; a < 3; ++a) {
    Candidate k = capsule_along(mesh.vertices, principal.centroid, principal.axes.col(a));
    if (k.volume < best.volume) best = k;
  }
  FittedShape fitted;
  fitted.shape = best.shape;
  fitted.in_mesh = best.in_mesh;
  fitted.over_approximation = largest_surface_gap(mesh, best.shape, best.in_mesh);
  return fitted;
}

double thinnest_extent(const TriangleMesh& mesh) {
  const Principal principal = principal_axes(mesh.vertices);
  const Eigen::Vector3d thin = principal.axes.col(0);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Eigen::Vector3d& v : mesh.vertices) {
    lo = std::min(lo, thin.dot(v));
    hi = std::max(hi, thin.dot(v));
  }
  return hi - lo;
}

double largest_surface_gap(const TriangleMesh& mesh, const Shape& shape, const Pose& in_mesh) {
  const std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> bvh = mesh_geometry(mesh);
  const fcl::Sphered point(1e-9);
  fcl::DistanceRequestd request;
  double gap = 0;
  for (const Eigen::Vector3d& p : surface_samples(shape, in_mesh)) {
    fcl::DistanceResultd result;
    fcl::Transform3d at = fcl::Transform3d::Identity();
    at.translation() = p;
    const double d =
        fcl::distance(&point, at, bvh.get(), fcl::Transform3d::Identity(), request, result);
    gap = std::max(gap, d);
  }
  return gap;
}

}  // namespace lazyboe
