#include "shatter/runtime/mass.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace shatter::runtime {

namespace {

bool finite_part(const MassProperties& part) {
  if (!std::isfinite(part.volume) || !is_finite(part.centroid)) return false;
  for (double value : part.inertia) {
    if (!std::isfinite(value)) return false;
  }
  return true;
}

// The principal axes as columns of a proper rotation, with a sign rule that
// does not depend on how the solver happened to sign them.
Eigen::Matrix3d right_handed_axes(const Eigen::Matrix3d& eigenvectors) {
  Eigen::Matrix3d axes = eigenvectors;
  for (int column = 0; column < 2; ++column) {
    Eigen::Index largest = 0;
    axes.col(column).cwiseAbs().maxCoeff(&largest);
    if (axes(largest, column) < 0) axes.col(column) = -axes.col(column);
  }
  axes.col(2) = axes.col(0).cross(axes.col(1)).normalized();
  return axes;
}

}  // namespace

RigidMass combine_masses(std::span<const MassProperties> parts, double density) {
  if (parts.empty()) throw std::invalid_argument("combine_masses: no parts");
  if (!(density > 0) || !std::isfinite(density)) {
    throw std::invalid_argument("combine_masses: the density must be positive and finite");
  }
  double volume = 0;
  Vec3 weighted_centroid;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (!finite_part(parts[i]) || !(parts[i].volume > 0)) {
      throw std::invalid_argument("combine_masses: part " + std::to_string(i) +
                                  " has a non-positive volume or a non-finite value");
    }
    volume += parts[i].volume;
    weighted_centroid = weighted_centroid + parts[i].centroid * parts[i].volume;
  }
  const Vec3 centroid = weighted_centroid * (1.0 / volume);

  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (const MassProperties& part : parts) {
    const Eigen::Vector3d d(part.centroid.x - centroid.x, part.centroid.y - centroid.y, part.centroid.z - centroid.z);
    const Eigen::Matrix3d own = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(part.inertia.data());
    inertia += own + part.volume * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  inertia *= density;
  // Summing in a different order than a mirror image would leaves the tensor a
  // few ulps from symmetric; the solver reads only the lower triangle anyway.
  inertia = (0.5 * (inertia + inertia.transpose())).eval();

  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(inertia);
  const Eigen::Matrix3d axes = right_handed_axes(solver.eigenvectors());
  const Eigen::Vector3d moments = solver.eigenvalues();

  RigidMass result;
  result.mass = density * volume;
  result.centroid = centroid;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) result.inertia[static_cast<std::size_t>(3 * r + c)] = inertia(r, c);
  }
  result.principal_moments = {moments(0), moments(1), moments(2)};
  Matrix3 rotation{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rotation[static_cast<std::size_t>(3 * r + c)] = axes(r, c);
  }
  result.frame = {centroid, quaternion_of(rotation)};
  return result;
}

RigidMass cluster_mass(const MeshTree& tree, std::span<const NodeIndex> nodes, double density) {
  std::vector<MassProperties> parts;
  parts.reserve(nodes.size());
  for (NodeIndex node : nodes) {
    if (node >= tree.nodes.size()) {
      throw std::invalid_argument("cluster_mass: node " + std::to_string(node) + " is not in the tree");
    }
    parts.push_back(tree.nodes[node].mass);
  }
  return combine_masses(parts, density);
}

}  // namespace shatter::runtime
