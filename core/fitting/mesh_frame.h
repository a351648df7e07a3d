#pragma once
// Where a body mesh made elsewhere stands: its unit, which file axis is up, which way it faces,
// and its arm pose, so that it can be brought into skinstream's axes (millimetres, +X the
// subject's right, +Y forward, +Z up; core/body/skeleton.h) before it is fitted. A template or a
// scan comes in mm, cm, dm or m, Y up or Z up, facing any direction about the vertical, in a T
// or an A pose.
//
// Detection, on the surface (area-weighted, so a finely meshed face weighs no more than its area):
//   left-right  the normal of the body's mirror plane: among the principal axes of the surface
//               (a mirror-symmetric shape has its mirror normal among them) and the file axes,
//               the plane whose mirror image of the surface lies closest to the surface, refined
//               by Gauss-Newton on the point-to-plane distances of the mirrored samples (the
//               worst 40% left out, so that an asymmetric pose still finds the body's plane;
//               of planes that mirror it equally well, the one across which it is slenderest);
//   vertical    the long axis within the mirror plane (a body is several times taller than
//               deep), snapped to a file axis when within 10 degrees of one (files are made
//               upright; a principal axis tilts by a degree or two with the feet forward);
//   up or down  the end where the body splits into two legs (slices of the lower part of the
//               height with no surface on the mirror plane and surface on both sides of it);
//   front       the soles reach further ahead of the ankles (toes) than behind them (heels);
//   unit        the one of mm, cm, dm, m that makes the height a human's (0.5 to 3 m);
//   arms        the direction from the shoulder joint (placed by adult proportions below the
//               top of the shoulders) to the far end of the arm's surface (beyond 0.16 of the
//               height from the mirror plane and above the crotch: the fingertips), as an angle
//               from hanging straight down.
// Overrides (MeshFrameOptions) replace a detection; the body checks still run, and an override
// the body contradicts (a unit giving an inhuman height, an up along which the body is not
// tall or stands on its head, a forward along its left-right axis) is refused.
#include <Eigen/Core>
#include <array>
#include <optional>
#include <span>
#include <vector>

#include "core/capture.h"
#include "core/geometry/triangle_mesh.h"

namespace skinstream {

struct MeshFrameOptions {       // overrides; unset = detect
  double unit_mm = 0.0;         // mm per file unit (1, 10, 100, 1000, or any positive value); 0 = detect
  std::optional<Vec3> up;       // file axis pointing up (e.g. (0, 1, 0)); any length
  std::optional<Vec3> forward;  // file axis the body faces; perpendicular to up when both given
};

struct MeshFrame {
  double unit_mm = 1.0;                                    // chosen or given
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // file axes -> skinstream axes; det +1
  Vec3 translation = Vec3::Zero();  // mm, after scale and rotation: lowest point at z = 0, the
                                    // mirror plane at x = 0, the surface's centroid at y = 0
  double height_mm = 0.0;
  // Arms from hanging straight down (degrees): about 45 in an A pose, 90 in a T pose; NaN when
  // an arm is too close to the body to be told apart (at the sides, or straight ahead).
  double arm_elevation_deg = 0.0;                  // mean of both sides
  std::array<double, 2> side_arm_elevation_deg{};  // left, right

  // How clear the detection was. Lengths are fractions of the height.
  double symmetry_residual = 0.0;  // median distance from the mirrored surface to the surface
  double symmetry_margin = 0.0;    // the same for the best other plane (> 20 degrees away;
                                   // the front-back one for a body); NaN when both axes given
  double height_to_depth = 0.0;    // extent along up / extent along forward
  double leg_split = 0.0;          // fraction of slices at 4-40% of the height, from the feet,
                                   // where left and right stand apart (1 for a standing body)
  double head_split = 0.0;         // the same from the top (0: a head and a torso on the plane)
  double toe_reach = 0.0;          // (toe reach - heel reach) ahead of the ankles at the soles,
                                   // mean of both feet (positive: the feet point forward)
  double up_tilt_deg = 0.0;        // detected long axis to the nearest file axis (snapped to it
                                   // when under 10 degrees; 0 when up or forward is given)
};

// vertices: #V positions in file units and axes; triangles: #F x 3 indices into them (winding
// not used). Returns the frame; throws std::invalid_argument with one line naming the problem:
// an empty mesh, an index out of range or a non-finite vertex; a mesh that is not a body ("the
// mesh is not a body: no mirror symmetry plane", "...: no two legs", ...); front and back that
// cannot be told apart (give `forward`); no unit giving a human height (give `unit_mm`); an
// override the body contradicts ("in metres the mesh would be 16.7 m tall").
MeshFrame detect_mesh_frame(std::span<const Vec3> vertices, std::span<const Triangle> triangles,
                            const MeshFrameOptions& options = {});

// #V file positions -> skinstream positions (mm): unit_mm * rotation * p + translation.
std::vector<Vec3> to_skinstream_axes(const MeshFrame& frame, std::span<const Vec3> vertices);

}  // namespace skinstream
