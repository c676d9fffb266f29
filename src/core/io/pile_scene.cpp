#include "implicit_sim/core/io/pile_scene.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

#include "implicit_sim/core/base/format.h"


namespace implicit_sim {
namespace {

void AddHalfSpace(std::ostringstream& out, const std::string& name, const std::string& xyz, const std::string& rpy) {
  // The half-space z <= 0 of the link frame; the stock box is a stand-in for URDF tools.
  out << "  <link name=\"" << name << "\">\n"
      << "    <visual><origin xyz=\"0 0 -0.01\"/><geometry><box size=\"1.2 1.2 0.02\"/></geometry></visual>\n"
      << "    <collision><geometry><box size=\"1.2 1.2 0.001\"/></geometry><implicit type=\"halfspace\"/></collision>\n"
      << "  </link>\n"
      << "  <joint name=\"" << name << "_joint\" type=\"fixed\"><parent link=\"world\"/><child link=\"" << name
      << "\"/><origin xyz=\"" << xyz << "\" rpy=\"" << rpy << "\"/></joint>\n";
}


// URDF's roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll)) of a rotation.
Vec3 RollPitchYaw(const Mat3& R) {
  return Vec3(std::atan2(R(2, 1), R(2, 2)), std::asin(std::clamp(-R(2, 0), -1.0, 1.0)), std::atan2(R(1, 0), R(0, 0)));
}

// Shoemake's uniform rotation from three uniforms in [0, 1).
Mat3 UniformRotation(double u1, double u2, double u3) {
  constexpr double kTwoPi = 6.283185307179586;
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  const Eigen::Quaterniond q(b * std::cos(kTwoPi * u3), a * std::sin(kTwoPi * u2), a * std::cos(kTwoPi * u2),
                             b * std::sin(kTwoPi * u3));  // w x y z
  return q.normalized().toRotationMatrix();
}

// A part's <inertial>, <visual> and <collision> elements (0.1 kg in all).
std::string PartElements(PileShape shape) {
  const double mass = 0.1;
  switch (shape) {
    case PileShape::kSphere:
    case PileShape::kEllipsoid: {
      const bool sphere = shape == PileShape::kSphere;
      const double a = sphere ? 0.05 : 0.06, b = 0.05, c = sphere ? 0.05 : 0.04;
      // Solid ellipsoid (a sphere when a = b = c): I_xx = m (b^2 + c^2) / 5, cyclic.
      const double ixx = mass * (b * b + c * c) / 5.0, iyy = mass * (a * a + c * c) / 5.0;
      const double izz = mass * (a * a + b * b) / 5.0;
      const std::string geometry = sphere ? "<sphere radius=\"0.05\"/>" : "<sphere radius=\"0.06\"/>";
      const std::string implicit = sphere ? "" : "<implicit type=\"ellipsoid\" semi_axes=\"0.06 0.05 0.04\"/>";
      return "    <inertial><mass value=\"" + FormatNumber(mass) + "\"/><inertia ixx=\"" + FormatNumber(ixx) +
             "\" iyy=\"" + FormatNumber(iyy) + "\" izz=\"" + FormatNumber(izz) +
             "\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>\n    <visual><geometry>" + geometry +
             "</geometry></visual>\n    <collision><geometry>" + geometry + "</geometry>" + implicit +
             "</collision>\n";
    }
    case PileShape::kBracket:
      // Two rounded boxes (superellipsoids of exponent 8) in an L, masses in the ratio of their box volumes (2 : 1);
      // the mass properties come from the union (doc/scenes.md#mass).
      return "    <visual><origin xyz=\"0 0 -0.0225\"/><geometry><box size=\"0.08 0.03 0.015\"/></geometry></visual>\n"
             "    <visual><origin xyz=\"-0.0325 0 0.005\"/><geometry><box size=\"0.015 0.03 0.04\"/></geometry></visual>\n"
             "    <collision><origin xyz=\"0 0 -0.0225\"/><geometry><box size=\"0.08 0.03 0.015\"/></geometry>"
             "<implicit type=\"superellipsoid\" semi_axes=\"0.04 0.015 0.0075\" exponent=\"8\" mass=\"" +
             FormatNumber(2.0 * mass / 3.0) + "\"/></collision>\n"
             "    <collision><origin xyz=\"-0.0325 0 0.005\"/><geometry><box size=\"0.015 0.03 0.04\"/></geometry>"
             "<implicit type=\"superellipsoid\" semi_axes=\"0.0075 0.015 0.02\" exponent=\"8\" mass=\"" +
             FormatNumber(mass / 3.0) + "\"/></collision>\n";
    case PileShape::kTee:
      // A solid pipe along x (r = 15 mm, 90 mm) with a branch along z (r = 12 mm, 40 mm) standing on its top line;
      // masses in the ratio of the cylinders' volumes.
      {
        const double main_volume = 0.015 * 0.015 * 0.09, branch_volume = 0.012 * 0.012 * 0.04;
        const double main_mass = mass * main_volume / (main_volume + branch_volume);
        const std::string main = "<origin xyz=\"0 0 -0.01\" rpy=\"0 1.5707963267948966 0\"/><geometry>"
                                 "<cylinder radius=\"0.015\" length=\"0.09\"/></geometry>";
        const std::string branch = "<origin xyz=\"0 0 0.025\"/><geometry><cylinder radius=\"0.012\" length=\"0.04\"/>"
                                   "</geometry>";
        return "    <visual>" + main + "</visual>\n    <visual>" + branch + "</visual>\n    <collision>" + main +
               "<implicit type=\"cylinder\" radius=\"0.015\" length=\"0.09\" mass=\"" + FormatNumber(main_mass) +
               "\"/></collision>\n    <collision>" + branch +
               "<implicit type=\"cylinder\" radius=\"0.012\" length=\"0.04\" mass=\"" +
               FormatNumber(mass - main_mass) + "\"/></collision>\n";
      }
  }
  throw std::invalid_argument("unknown pile shape");
}

// The pile's URDF with body i at pose X_WB[i], the torsional lever e_r and rolling resistance e_roll (m; 0: none);
// `random_orientations` only changes the comment.
std::string PileUrdf(int n, PileShape shape, unsigned seed, const std::vector<Pose>& X_WB, int separated_pairs,
                     double max_shift, double e_r, double e_roll, bool random_orientations = false) {
  const std::string shape_name = PileShapeName(shape);
  std::ostringstream out;
  out << "<?xml version=\"1.0\"?>\n<!-- S1 pile: " << n << " " << shape_name << " parts, seed " << seed
      << "; generated by implicit_sim_make_pile (see include/implicit_sim/core/io/pile_scene.h)";
  if (random_orientations) out << ". Random orientations (uniform on SO(3)), 7 x 7 per layer at 0.14 m spacing";
  if (separated_pairs > 0) {
    out << ". The scenario's layout lets x-neighbours overlap; the rows are spread to 0.12 m spacing (least squares, "
        << separated_pairs << " bodies moved along x, largest shift " << FormatNumber(max_shift) << " m)";
  }
  out << ". -->\n<robot name=\"s1_pile_" << n << "_" << shape_name << "\">\n"
      << "  <implicit_sim gravity=\"0 0 -9.81\">\n    <friction mu=\"0.5\" e_t=\"1\" e_o=\"1\" e_r=\""
      << FormatNumber(e_r) << "\"";
  if (e_roll > 0.0) out << " e_roll=\"" << FormatNumber(e_roll) << "\"";
  out << "/>\n  </implicit_sim>\n  <link name=\"world\"/>\n";
  AddHalfSpace(out, "floor", "0 0 0", "0 0 0");
  AddHalfSpace(out, "wall_px", "0.5 0 0", "0 -1.5707963267948966 0");   // occupies x >= 0.5
  AddHalfSpace(out, "wall_nx", "-0.5 0 0", "0 1.5707963267948966 0");   // occupies x <= -0.5
  AddHalfSpace(out, "wall_py", "0 0.5 0", "1.5707963267948966 0 0");    // occupies y >= 0.5
  AddHalfSpace(out, "wall_ny", "0 -0.5 0", "-1.5707963267948966 0 0");  // occupies y <= -0.5
  const std::string part = PartElements(shape);
  for (int i = 0; i < n; ++i) {
    const std::string name = "body_" + std::to_string(i);
    const Vec3 p = X_WB[i].translation();
    const Vec3 rpy = RollPitchYaw(X_WB[i].linear());
    out << "  <link name=\"" << name << "\">\n" << part << "  </link>\n"
        << "  <joint name=\"" << name << "_joint\" type=\"floating\"><parent link=\"world\"/><child link=\"" << name
        << "\"/><origin xyz=\"" << FormatNumber(p.x()) << " " << FormatNumber(p.y()) << " " << FormatNumber(p.z())
        << "\" rpy=\"" << FormatNumber(rpy.x()) << " " << FormatNumber(rpy.y()) << " " << FormatNumber(rpy.z())
        << "\"/></joint>\n";
  }
  out << "</robot>\n";
  return out.str();
}

}  // namespace

std::string PileShapeName(PileShape shape) {
  switch (shape) {
    case PileShape::kSphere: return "sphere";
    case PileShape::kEllipsoid: return "ellipsoid";
    case PileShape::kBracket: return "bracket";
    case PileShape::kTee: return "tee";
  }
  throw std::invalid_argument("unknown pile shape");
}

bool ParsePileShape(const std::string& name, PileShape* shape) {
  for (PileShape candidate : {PileShape::kSphere, PileShape::kEllipsoid, PileShape::kBracket, PileShape::kTee}) {
    if (PileShapeName(candidate) == name) {
      *shape = candidate;
      return true;
    }
  }
  return false;
}

std::vector<Pose> PileLayout(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.01, 0.01);
  std::vector<Pose> X_WB(n, Pose::Identity());
  for (int i = 0; i < n; ++i) {
    const int layer = i / 64, row = (i / 8) % 8, col = i % 8;
    const double j1 = jitter(rng), j2 = jitter(rng), j3 = jitter(rng);
    X_WB[i].translation() = Vec3(-0.42 + 0.12 * col + j1, -0.42 + 0.12 * row + j2, 0.08 + 0.12 * layer + std::abs(j3));
  }
  return X_WB;
}

std::vector<Pose> RandomPileLayout(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.01, 0.01), uniform(0.0, 1.0);
  std::vector<Pose> X_WB(n, Pose::Identity());
  for (int i = 0; i < n; ++i) {
    const int layer = i / 49, row = (i / 7) % 7, col = i % 7;
    const double j1 = jitter(rng), j2 = jitter(rng), j3 = jitter(rng);
    const double u1 = uniform(rng), u2 = uniform(rng), u3 = uniform(rng);
    X_WB[i].translation() = Vec3(-0.42 + 0.14 * col + j1, -0.42 + 0.14 * row + j2, 0.08 + 0.14 * layer + std::abs(j3));
    X_WB[i].linear() = UniformRotation(u1, u2, u3);
  }
  return X_WB;
}

int SeparateRows(std::vector<Pose>* X_WB, double length) {
  const int n = static_cast<int>(X_WB->size());
  int moved = 0;
  for (int first = 0; first < n; first += 8) {  // one row: bodies first .. first + 7, ascending x
    const int count = std::min(8, n - first);
    // y_i = x_i - length i must be non-decreasing: least squares by pool-adjacent-violators.
    std::vector<double> value, weight;
    std::vector<int> size;
    for (int i = 0; i < count; ++i) {
      value.push_back((*X_WB)[first + i].translation().x() - length * i);
      weight.push_back(1.0);
      size.push_back(1);
      while (value.size() > 1 && value[value.size() - 2] > value.back()) {
        const double w = weight[weight.size() - 2] + weight.back();
        const double v = (value[value.size() - 2] * weight[weight.size() - 2] + value.back() * weight.back()) / w;
        const int merged = size[size.size() - 2] + size.back();
        value.pop_back(), weight.pop_back(), size.pop_back();
        value.back() = v, weight.back() = w, size.back() = merged;
      }
    }
    for (size_t block = 0, i = 0; block < value.size(); ++block) {
      for (int k = 0; k < size[block]; ++k, ++i) {
        double& x = (*X_WB)[first + i].translation().x();
        const double projected = value[block] + length * static_cast<double>(i);
        moved += std::abs(projected - x) > 0.0;
        x = projected;
      }
    }
  }
  return moved;
}

int MaxPileSize(PileShape shape) {
  return shape == PileShape::kSphere || shape == PileShape::kEllipsoid ? 4000 : 2000;
}

std::string MakePileUrdf(int n, PileShape shape, unsigned seed, bool separate_overlaps, PileOrientation orientation,
                         double e_roll, double e_r) {
  if (n < 1 || n > MaxPileSize(shape)) {
    throw std::invalid_argument("pile size n must be in [1, " + std::to_string(MaxPileSize(shape)) + "] for " +
                                PileShapeName(shape) + " parts (every pair of shapes is stored: " +
                                "Model::kMaxContactPairs), got " + std::to_string(n));
  }
  if (!(e_r >= 0.0 && e_r <= 1000.0)) {
    throw std::invalid_argument("pile e_r must be in [0, 1000] m, got " + FormatNumber(e_r));
  }
  if (!(e_roll >= 0.0 && e_roll <= 1000.0)) {
    throw std::invalid_argument("pile e_roll must be in [0, 1000] m, got " + FormatNumber(e_roll));
  }
  if (orientation == PileOrientation::kRandom) {
    return PileUrdf(n, shape, seed, RandomPileLayout(n, seed), 0, 0.0, e_r, e_roll, true);
  }
  std::vector<Pose> X_WB = PileLayout(n, seed);
  const std::string layout = PileUrdf(n, shape, seed, X_WB, 0, 0.0, e_r, e_roll);
  if (!separate_overlaps || shape != PileShape::kEllipsoid) return layout;  // only ellipsoids overlap
  const std::vector<Pose> original = X_WB;
  const int separated = SeparateRows(&X_WB, 0.12);
  if (separated == 0) return layout;
  double max_shift = 0.0;
  for (int k = 0; k < n; ++k) max_shift = std::max(max_shift, (X_WB[k].translation() - original[k].translation()).norm());
  return PileUrdf(n, shape, seed, X_WB, separated, max_shift, e_r, e_roll);
}

}  // namespace implicit_sim
