#pragma once
// Section 5.1: fits a detailed mesh (an artist's model) to the marker surface of the reference
// pose, after Allen, Curless & Popovic 2003. Every vertex j gets its own affine transform X_j
// (4 x 3, acting on the homogeneous row [v_j^T 1]); the registered vertex is [v_j^T 1] X_j.
// The transforms minimise
//   w_data      * mean_markers   |closest point of the deformed surface - (marker - offset * n)|^2
// + w_smooth    * mean_edges     ||X_i - X_j||_F^2
// + w_landmark  * mean_landmarks |[v^T 1] X - (marker - offset * n)|^2
// Each term is a mean (Allen et al. sum): equal weights then give each term the same say
// whatever the mesh resolution and the number of markers.
// (+ a tiny damping toward the previous transforms, so that the system is always positive
// definite, e.g. with fewer than 4 landmarks). Closest points are recomputed every outer
// iteration and each iteration is one sparse linear solve (SimplicialLDLT on the normal
// equations; the three output coordinates share the matrix). As in the paper, a first phase
// uses only smoothness and landmarks (a global fit), then all terms with their weights.
//
// Coordinates are centred on the mesh centroid and divided by its RMS radius internally, so the
// weights do not depend on the unit or the size of the body; inputs and outputs are in mm.

#include <array>
#include <span>
#include <vector>

#include "core/capture.h"

namespace skinstream {

// A marker <-> vertex correspondence that is known (elbow, knee...): the registered vertex
// should reach the marker (minus the skin offset along the vertex normal). With a triangle, the
// correspondence is a point of that triangle instead (barycentric; `vertex` is then unused), as
// a fitted template knows where each marker sits between vertices.
struct RegistrationLandmark {
  int marker = 0;  // index into the markers
  int vertex = 0;  // index into the mesh vertices
  int triangle = -1;                    // >= 0: the landmark is this triangle's point ...
  Vec3 barycentric = Vec3::Zero();      // ... at these barycentric coordinates
  bool operator==(const RegistrationLandmark&) const = default;
};

struct RegistrationOptions {
  double data_weight = 1.0;       // second phase; the first phase uses 0
  double smoothness_weight = 1.0;
  double landmark_weight = 1.0;
  double damping_weight = 1e-6;   // toward the previous iterate; keeps the system definite
  double marker_offset_mm = 0.0;  // markers sit this far above the skin along its normal
  bool global_phase = true;       // run the smoothness + landmarks phase first
  int max_iterations = 20;        // outer iterations of the second phase
  double tolerance_mm = 0.01;     // stop when the mean marker distance improves less than this
};

// Marker-to-surface distance statistics (mm): | |marker - closest surface point| - offset |.
struct SurfaceDistance {
  double mean = 0.0, rms = 0.0, max = 0.0;
};

struct RegistrationReport {
  SurfaceDistance before;           // the mesh as given
  SurfaceDistance after_global;     // after the first phase (equal to `before` when skipped)
  SurfaceDistance after;            // the registered mesh
  double landmark_rms_before_mm = 0.0;  // |vertex - (marker - offset n)| over the landmarks
  double landmark_rms_after_mm = 0.0;
  double landmark_max_after_mm = 0.0;
  int iterations = 0;               // linear solves, both phases
};

// vertices: #V mesh vertex positions (mm); triangles: #F x 3 vertex indices, counter-clockwise
// seen from outside (the normal offset points outward); markers: #M marker positions of the
// reference pose (mm, all finite); landmarks: at least one pair.
// Returns the #V registered vertex positions (mm), same order. Throws std::invalid_argument
// (one line naming the problem) for an empty mesh, no landmarks, an index out of range, a
// non-finite value or a negative weight/offset.
std::vector<Vec3> register_mesh(std::span<const Vec3> vertices, std::span<const std::array<int, 3>> triangles,
                                std::span<const Vec3> markers, std::span<const RegistrationLandmark> landmarks,
                                const RegistrationOptions& options = {}, RegistrationReport* out_report = nullptr);

// Distance of each marker to a mesh (statistics as in the report).
SurfaceDistance marker_surface_distance(std::span<const Vec3> vertices, std::span<const std::array<int, 3>> triangles,
                                        std::span<const Vec3> markers, double marker_offset_mm = 0.0);

struct LandmarkGuessOptions {
  int alignment_iterations = 50;  // ICP rounds at most (stops when the pairs no longer change)
  // Keep a marker only when its nearest aligned vertex is this close (mm, after alignment);
  // infinity keeps every marker.
  double max_distance_mm = 1e30;
};

// Landmarks when none are given: aligns the mesh to the markers by a similarity (centroids and
// RMS radii first, then ICP rounds of nearest vertex + Horn fit with scale; the mesh must face
// roughly the same way as the markers, no rotation search is made), then pairs every marker with
// its nearest aligned vertex. Meant for a mesh that is already close to the marker surface
// (same subject, same pose, roughly the same axes): then every marker is a good landmark. For an
// unrelated mesh, give landmarks from a file. Sorted by marker; deterministic. Throws
// std::invalid_argument for an empty or non-finite input.
std::vector<RegistrationLandmark> guess_landmarks(std::span<const Vec3> vertices, std::span<const Vec3> markers,
                                                  const LandmarkGuessOptions& options = {});

}  // namespace skinstream
