#include "core/fitting/mesh_frame.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <string>

#include "tests/core/fitting/fitting_test_support.h"

namespace skinstream {
namespace {

using test::template_body;

// MakeHuman's file axes (dm, Y up, facing +Z, left on +X) to skinstream's.
const Eigen::Matrix3d kMakeHumanToSkinstream = (Eigen::Matrix3d() << -1, 0, 0, 0, 0, 1, 0, 1, 0).finished();

double angle_deg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a * b.transpose()).angle() * 180.0 / M_PI;
}

std::vector<Vec3> transformed(std::span<const Vec3> points, const Eigen::Matrix3d& r, double scale) {
  std::vector<Vec3> out;
  for (const Vec3& p : points) out.push_back(scale * (r * p));
  return out;
}

// The message of the std::invalid_argument `f` throws ("" when it throws none).
template <class F>
std::string refusal(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

bool one_line(const std::string& s) { return !s.empty() && s.find('\n') == std::string::npos; }

TEST(MeshFrame, RejectsBadInputWithOneLine) {
  const auto& t = template_body();
  const std::vector<Vec3> none;
  const std::vector<Triangle> no_triangles;
  EXPECT_TRUE(one_line(refusal([&] { detect_mesh_frame(none, no_triangles); })));
  EXPECT_TRUE(one_line(refusal([&] { detect_mesh_frame(t.file.vertices, no_triangles); })));
  std::vector<Triangle> out_of_range = t.triangles;
  out_of_range[7][2] = static_cast<int>(t.file.vertices.size());
  EXPECT_NE(refusal([&] { detect_mesh_frame(t.file.vertices, out_of_range); }).find("triangle 7"),
            std::string::npos);
  std::vector<Vec3> not_finite = t.file.vertices;
  not_finite[3].y() = std::nan("");
  EXPECT_NE(refusal([&] { detect_mesh_frame(not_finite, t.triangles); }).find("vertex 3"), std::string::npos);
  const std::vector<Vec3> flat(4, Vec3::Zero());
  const std::vector<Triangle> two{{0, 1, 2}, {0, 2, 3}};
  EXPECT_NE(refusal([&] { detect_mesh_frame(flat, two); }).find("no area"), std::string::npos);
  MeshFrameOptions negative_unit;
  negative_unit.unit_mm = -10.0;
  EXPECT_TRUE(one_line(refusal([&] { detect_mesh_frame(t.file.vertices, t.triangles, negative_unit); })));
  MeshFrameOptions zero_up;
  zero_up.up = Vec3::Zero();
  EXPECT_NE(refusal([&] { detect_mesh_frame(t.file.vertices, t.triangles, zero_up); }).find("up axis"),
            std::string::npos);
  MeshFrameOptions skew;
  skew.up = Vec3(0, 1, 0);
  skew.forward = Vec3(0, 1, 1);
  EXPECT_NE(refusal([&] { detect_mesh_frame(t.file.vertices, t.triangles, skew); }).find("not perpendicular"),
            std::string::npos);
}

TEST(MeshFrame, RefusesShapesThatAreNotBodies) {
  const std::vector<std::pair<std::string, test::Shape>> shapes = {
      {"sphere", test::sphere(900.0)},
      {"box", test::box(Vec3(0.5, 0.3, 1.8))},
      {"cylinder", test::cylinder(200.0, 1700.0)},
      {"plane", test::plane(0.5, 1.7)},
      {"blob 1", test::blob(9.0, 1)},
      {"blob 2", test::blob(9.0, 2)},
      {"blob 3", test::blob(9.0, 3)},
  };
  for (const auto& [name, shape] : shapes) {
    const std::string why = refusal([&] { detect_mesh_frame(shape.vertices, shape.triangles); });
    EXPECT_TRUE(one_line(why)) << name;
    EXPECT_EQ(why.rfind("the mesh is not a body: ", 0), 0u) << name << ": " << why;
    std::printf("mesh frame: %s refused: %s\n", name.c_str(), why.c_str());
  }
}

TEST(MeshFrame, TemplateAsShippedNeedsNoFlag) {
  const auto& t = template_body();
  const MeshFrame f = detect_mesh_frame(t.file.vertices, t.triangles);
  EXPECT_EQ(f.unit_mm, 100.0);
  EXPECT_LT(angle_deg(f.rotation, kMakeHumanToSkinstream), 1e-6);
  EXPECT_NEAR(f.rotation.determinant(), 1.0, 1e-12);
  EXPECT_NEAR(f.height_mm, 1666.0, 1.0);
  // In skinstream axes it is the loaded body up to a shift along the floor: the lowest point on
  // z = 0, the mirror plane on x = 0.
  const std::vector<Vec3> placed = to_skinstream_axes(f, t.file.vertices);
  double lowest = 1e30, min_x = 1e30, max_x = -1e30;
  for (const Vec3& p : placed) {
    lowest = std::min(lowest, p.z());
    min_x = std::min(min_x, p.x());
    max_x = std::max(max_x, p.x());
  }
  EXPECT_NEAR(lowest, 0.0, 1e-9);
  EXPECT_NEAR(min_x + max_x, 0.0, 1e-6);
  const Vec3 shift = placed[0] - t.body.rest[0];
  for (size_t v = 0; v < placed.size(); v += 97)
    EXPECT_LT((placed[v] - t.body.rest[v] - shift).norm(), 1e-6) << v;
  // A clear detection: a plane that mirrors the surface exactly, the legs apart in every low
  // slice and nowhere at the top, toes 6% of the height further ahead than the heels behind.
  EXPECT_LT(f.symmetry_residual, 1e-4);
  EXPECT_GT(f.leg_split, 0.99);
  EXPECT_LT(f.head_split, 0.01);
  EXPECT_GT(f.toe_reach, 0.05);
  EXPECT_GT(f.height_to_depth, 3.5);
  std::printf(
      "mesh frame, template as shipped: unit %g mm, height %.1f mm, arms %.1f deg; symmetry residual %.2g, "
      "next plane "
      "%.4f of the height; height/depth %.2f; legs apart in %.0f%% of the low slices, %.0f%% at the top; toe "
      "reach "
      "%.3f; up tilt %.2f deg\n",
      f.unit_mm, f.height_mm, f.arm_elevation_deg, f.symmetry_residual, f.symmetry_margin, f.height_to_depth,
      100.0 * f.leg_split, 100.0 * f.head_split, f.toe_reach, f.up_tilt_deg);
}

TEST(MeshFrame, AllAxisAlignedOrientationsInEveryUnit) {
  // The template in skinstream axes (mm), turned to each of the 24 rotations that map axes to
  // axes and written in mm, cm, dm and m.
  const auto& t = template_body();
  int cases = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      if (b == a) continue;
      for (double sa : {-1.0, 1.0})
        for (double sb : {-1.0, 1.0}) {
          Eigen::Matrix3d q = Eigen::Matrix3d::Zero();  // skinstream -> file
          q(a, 0) = sa;
          q(b, 1) = sb;
          q.col(2) = q.col(0).cross(q.col(1));
          for (double unit : {1.0, 10.0, 100.0, 1000.0}) {
            const MeshFrame f = detect_mesh_frame(transformed(t.body.rest, q, 1.0 / unit), t.triangles);
            EXPECT_EQ(f.unit_mm, unit) << q << "\n";
            EXPECT_LT(angle_deg(f.rotation, q.transpose()), 1e-6) << q << "\nunit " << unit;
            EXPECT_NEAR(f.height_mm, 1666.0, 1.0);
            ++cases;
          }
        }
    }
  EXPECT_EQ(cases, 96);
}

TEST(MeshFrame, FacingAtAnyYaw) {
  // As shipped (Y up, dm), turned about the vertical every 15 degrees.
  const auto& t = template_body();
  double worst = 0.0;
  for (int yaw = 0; yaw < 360; yaw += 15) {
    const Eigen::Matrix3d q = Eigen::AngleAxisd(yaw * M_PI / 180.0, Vec3::UnitY()).toRotationMatrix();
    const MeshFrame f = detect_mesh_frame(transformed(t.file.vertices, q, 1.0), t.triangles);
    const double error = angle_deg(f.rotation, kMakeHumanToSkinstream * q.transpose());
    EXPECT_LT(error, 1.0) << "yaw " << yaw;
    EXPECT_EQ(f.unit_mm, 100.0);
    worst = std::max(worst, error);
  }
  std::printf("mesh frame: facing at 24 yaw angles, worst error %.2g deg\n", worst);
}

TEST(MeshFrame, ArmElevationTellsTPoseFromAPose) {
  const auto& t = template_body();
  const auto rest = [](PoseBuilder&) {};
  const auto t_pose = [](PoseBuilder& p) {
    for (Side s : {kLeft, kRight}) {
      p.shoulder(s, 0.0, 90.0);
      p.elbow(s, 0.0);
    }
  };
  const auto a_pose = [](PoseBuilder& p) {
    for (Side s : {kLeft, kRight}) {
      p.shoulder(s, 0.0, 45.0);
      p.elbow(s, 0.0);
    }
  };
  const struct {
    const char* name;
    std::vector<Vec3> vertices;
    double truth;
  } poses[] = {
      {"as shipped", t.body.rest, test::true_arm_elevation(kLeft, rest)},
      {"T pose", test::posed_template(t_pose), test::true_arm_elevation(kLeft, t_pose)},
      {"A pose 45", test::posed_template(a_pose), test::true_arm_elevation(kLeft, a_pose)},
  };
  for (const auto& pose : poses) {
    // Written Y up in cm, facing -X.
    const Eigen::Matrix3d q = (Eigen::Matrix3d() << 0, -1, 0, 0, 0, 1, -1, 0, 0).finished();
    const MeshFrame f = detect_mesh_frame(transformed(pose.vertices, q, 0.1), t.triangles);
    EXPECT_LT(angle_deg(f.rotation, q.transpose()), 1e-6) << pose.name;
    EXPECT_EQ(f.unit_mm, 10.0) << pose.name;
    // The fingertips hang a little below the wrist's line: within 6 degrees of shoulder-wrist.
    EXPECT_NEAR(f.arm_elevation_deg, pose.truth, 6.0) << pose.name;
    EXPECT_NEAR(f.side_arm_elevation_deg[0], f.side_arm_elevation_deg[1], 1e-6) << pose.name;
    std::printf("mesh frame, %s: arm elevation %.1f deg (shoulder to wrist %.1f)\n", pose.name,
                f.arm_elevation_deg, pose.truth);
  }
}

TEST(MeshFrame, ReproportionedBody) {
  // Longer legs (+15% below the hips), longer arms (+12% from the shoulders, through the skin
  // weights so the armpits stay joined), a wider body (+15% left to right), written Z up in m,
  // facing +X.
  const auto& t = template_body();
  const Anatomy& a = t.anatomy;
  std::vector<Vec3> body = t.body.rest;
  const double hip = a.hip_centre.z();
  for (int v = 0; v < t.body.vertex_count(); ++v) {
    Vec3& p = body[static_cast<size_t>(v)];
    for (Side s : {kLeft, kRight}) {
      double w = 0.0;
      for (int b = 0; b < t.body.skeleton.size(); ++b)
        if (t.body.skeleton.is_descendant(b, a.arm[s].upperarm)) w += t.body.weights.weight(v, b);
      p += w * 0.12 * (p - a.shoulder_joint[s]);
    }
    p.z() = p.z() < hip ? 1.15 * p.z() : p.z() + 0.15 * hip;
    p.x() *= 1.15;
  }
  const Eigen::Matrix3d q = (Eigen::Matrix3d() << 0, 1, 0, -1, 0, 0, 0, 0, 1).finished();
  const MeshFrame f = detect_mesh_frame(transformed(body, q, 1e-3), t.triangles);
  EXPECT_EQ(f.unit_mm, 1000.0);
  EXPECT_LT(angle_deg(f.rotation, q.transpose()), 1e-6);
  EXPECT_NEAR(f.height_mm, 1666.0 + 0.15 * hip, 5.0);
  std::printf("mesh frame, reproportioned: height %.0f mm, arms %.1f deg, toe reach %.3f\n", f.height_mm,
              f.arm_elevation_deg, f.toe_reach);
}

TEST(MeshFrame, AsymmetricPose) {
  // One arm out, the other reaching forward, a knee bent and the head turned: the mirror plane
  // is fitted to the 60% of the surface that still mirrors.
  const auto& t = template_body();
  const std::vector<Vec3> posed = test::posed_template([](PoseBuilder& p) {
    p.shoulder(kLeft, 0.0, 90.0);
    p.shoulder(kRight, 60.0, 30.0);
    p.knee(kRight, 40.0);
    p.neck(0.0, 0.0, 30.0);
  });
  const MeshFrame f = detect_mesh_frame(posed, t.triangles);
  EXPECT_EQ(f.unit_mm, 1.0);
  EXPECT_LT(angle_deg(f.rotation, Eigen::Matrix3d::Identity()), 1.0);
  EXPECT_GT(f.side_arm_elevation_deg[0], 80.0);
  std::printf(
      "mesh frame, asymmetric pose: facing error %.2f deg, symmetry residual %.4f, arms %.1f / %.1f deg\n",
      angle_deg(f.rotation, Eigen::Matrix3d::Identity()), f.symmetry_residual, f.side_arm_elevation_deg[0],
      f.side_arm_elevation_deg[1]);
}

TEST(MeshFrame, ArmsReachingForward) {
  // Arms straight ahead: the body is then slenderer seen from the side than from the front, but
  // only the left-right plane mirrors it. The arms are not told apart from the body sideways.
  const auto& t = template_body();
  const std::vector<Vec3> posed = test::posed_template([](PoseBuilder& p) {
    for (Side s : {kLeft, kRight}) {
      p.shoulder(s, 90.0, 90.0);
      p.elbow(s, 0.0);
    }
  });
  const MeshFrame f = detect_mesh_frame(posed, t.triangles);
  EXPECT_LT(angle_deg(f.rotation, Eigen::Matrix3d::Identity()), 1e-6);
  EXPECT_TRUE(std::isnan(f.arm_elevation_deg));
}

TEST(MeshFrame, UnitFlagIsCheckedAndNoUnitIsRefused) {
  const auto& t = template_body();
  MeshFrameOptions metres;
  metres.unit_mm = 1000.0;
  const std::string why = refusal([&] { detect_mesh_frame(t.file.vertices, t.triangles, metres); });
  EXPECT_TRUE(one_line(why));
  EXPECT_NE(why.find("in metres the mesh would be 16.7 m tall"), std::string::npos) << why;
  MeshFrameOptions centimetres;
  centimetres.unit_mm = 10.0;
  EXPECT_NE(refusal([&] {
              detect_mesh_frame(t.file.vertices, t.triangles, centimetres);
            }).find("in centimetres the mesh would be 0.167 m tall"),
            std::string::npos);
  MeshFrameOptions decimetres;
  decimetres.unit_mm = 100.0;
  EXPECT_EQ(detect_mesh_frame(t.file.vertices, t.triangles, decimetres).unit_mm, 100.0);
  MeshFrameOptions inches;  // any positive unit is taken when it gives a human height
  inches.unit_mm = 25.4;
  EXPECT_NEAR(detect_mesh_frame(transformed(t.body.rest, Eigen::Matrix3d::Identity(), 1.0 / 25.4),
                                t.triangles, inches)
                  .height_mm,
              1666.0, 1.0);
  // A body 1.7 mm tall in a file of metres (or 17 microns in mm): no unit fits.
  const std::string tiny = refusal([&] {
    detect_mesh_frame(transformed(t.file.vertices, Eigen::Matrix3d::Identity(), 1e-4), t.triangles);
  });
  EXPECT_TRUE(one_line(tiny));
  EXPECT_NE(tiny.find("0.001666 units tall"), std::string::npos) << tiny;
  EXPECT_NE(tiny.find("give the unit"), std::string::npos) << tiny;
}

TEST(MeshFrame, AxisFlagsAreUsedOrRefusedWhenTheBodyContradictsThem) {
  const auto& t = template_body();
  const auto frame = [&](std::optional<Vec3> up, std::optional<Vec3> forward) {
    MeshFrameOptions o;
    o.up = up;
    o.forward = forward;
    return detect_mesh_frame(t.file.vertices, t.triangles, o);
  };
  EXPECT_LT(angle_deg(frame(Vec3(0, 2, 0), std::nullopt).rotation, kMakeHumanToSkinstream), 1e-6);
  EXPECT_LT(angle_deg(frame(std::nullopt, Vec3(0, 0, 1)).rotation, kMakeHumanToSkinstream), 1e-6);
  EXPECT_LT(angle_deg(frame(Vec3(0, 1, 0), Vec3(0, 0, 1)).rotation, kMakeHumanToSkinstream), 1e-6);
  // Facing the other way is the user's call (the feet are not second-guessed).
  const MeshFrame back = frame(std::nullopt, Vec3(0, 0, -1));
  EXPECT_LT((back.rotation * Vec3(0, 0, -1) - Vec3(0, 1, 0)).norm(), 1e-9);
  EXPECT_LT((back.rotation * Vec3(0, 1, 0) - Vec3(0, 0, 1)).norm(), 1e-9);
  // Upside down, an up along the depth, a forward along the left-right axis: refused, saying
  // how the body stands.
  for (const auto& [up, forward] : std::vector<std::pair<std::optional<Vec3>, std::optional<Vec3>>>{
           {Vec3(0, -1, 0), std::nullopt}, {Vec3(0, 0, 1), std::nullopt}, {std::nullopt, Vec3(1, 0, 0)}}) {
    const std::string why = refusal([&] { frame(up, forward); });
    EXPECT_TRUE(one_line(why));
    EXPECT_NE(why.find("does not fit the body, which stands up along (0, 1, 0) and faces (0, 0, 1)"),
              std::string::npos)
        << why;
  }
}

TEST(MeshFrame, FeetPointingBothWaysNeedTheForwardFlag) {
  // The right shank and foot mirrored front to back about the ankle: one foot points forward,
  // the other backward, and nothing else is read for the facing.
  const auto& t = template_body();
  const Anatomy& a = t.anatomy;
  std::vector<Vec3> body = t.body.rest;
  for (Vec3& p : body)
    if (p.x() > 0.0 && p.z() < a.knee_joint[kRight].z()) p.y() = 2.0 * a.ankle_joint[kRight].y() - p.y();
  const std::string why = refusal([&] { detect_mesh_frame(body, t.triangles); });
  EXPECT_TRUE(one_line(why));
  EXPECT_NE(why.find("cannot tell the body's front from its back"), std::string::npos) << why;
  EXPECT_NE(why.find("give the forward axis"), std::string::npos) << why;
  MeshFrameOptions facing;
  facing.forward = Vec3(0, 1, 0);
  EXPECT_LT(angle_deg(detect_mesh_frame(body, t.triangles, facing).rotation, Eigen::Matrix3d::Identity()),
            1e-6);
}

}  // namespace
}  // namespace skinstream
