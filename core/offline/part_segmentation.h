#pragma once
// Section 5.2, first half: near-rigid segmentation of the marker surface, after James & Twigg
// 2005. Every marker-surface triangle gets a rotation sequence over the training take (the
// rotation part, by polar decomposition, of the deformation gradient that takes the triangle's
// reference frame [e1 e2 n] to its frame at t). Mean shift with a Gaussian kernel groups the
// triangles whose sequences are close (distance: RMS over sampled frames of the Frobenius
// distance between the rotations, 2 sqrt(2) sin(angle / 2), so the bandwidth is an angle).
// The paper then adjusts the result by hand into 17 parts; here the groups are split into
// connected pieces, then adjacent pairs (sharing a marker) are merged until the target count is
// reached: while a group is tiny, the smallest one merges with its best neighbour; otherwise the
// pair whose rigid fit error over the take grows least when fitted as one body (Ward's
// criterion on the summed squared residual of Horn fits over the sampled frames). Every triangle ends in exactly one part; every part is connected.

#include <array>
#include <span>
#include <vector>

#include "core/capture.h"

namespace skinstream {

struct SegmentationOptions {
  int target_parts = 17;
  double bandwidth_degrees = 3.0;  // mean-shift kernel width, as a rotation angle (small:
                                   // over-segment, the merging does the rest)
  int sample_frames = 40;           // frames of the take used (evenly spaced, first and last kept)
  int max_mean_shift_iterations = 50;
  // A group with fewer triangles than this is merged before any other merge is considered.
  int tiny_part_triangles = 4;
};

struct PartSegmentation {
  std::vector<int> triangle_part;   // #T, part index in [0, part_count)
  int part_count = 0;
  std::vector<double> part_rigid_rms_mm;  // #parts: RMS residual of the part's markers after
                                          // the best rigid fit per sampled frame
  int mean_shift_groups = 0;        // modes found by mean shift
  int connected_groups = 0;         // after splitting modes into connected pieces
  std::vector<int> unused_parts;    // a user's part indices that hold no triangle (dropped)
};

// reference: #M marker positions of the reference pose (mm); triangles: #T x 3 marker indices
// (the marker surface); positions: frame_count x #M marker positions, frame-major
// (positions[frame * #M + marker]), all present (a cleaned take, e.g. filled or the truth).
// Parts are numbered by their lowest triangle index. Deterministic. Throws
// std::invalid_argument for no triangles, an index out of range, a size mismatch, a non-finite
// position or bad options. A surface in several pieces ends with at least one part per piece.
PartSegmentation segment_parts(std::span<const Vec3> reference, std::span<const std::array<int, 3>> triangles,
                               std::span<const Vec3> positions, int frame_count, const SegmentationOptions& options = {});

enum class AssignmentKind { PerTriangle, PerMarker };

// A user's segmentation instead: `assignment` holds one part index per triangle (#T entries)
// or per marker (#M entries; a triangle takes the part most of its markers have, ties to the
// lowest part index). A part may be disconnected (the user's choice), but every part must hold
// a triangle: indices that end with none (unused, or outvoted on every triangle) are listed in
// unused_parts and the others renumbered in their order (0, 1, ...; unchanged when none is
// unused). The rigid residuals are measured; mean_shift_groups and connected_groups are 0.
// Throws std::invalid_argument for a wrong length, a negative index, an index not below the
// triangle count, or the errors of segment_parts.
PartSegmentation segmentation_from_assignment(std::span<const Vec3> reference, std::span<const std::array<int, 3>> triangles,
                                              std::span<const Vec3> positions, int frame_count,
                                              std::span<const int> assignment, AssignmentKind kind,
                                              int sample_frames = 40);

// Each marker's part in a user's terms: the part holding most of the marker's triangles (ties
// to the lowest part index), -1 for a marker in no triangle. It is what
// segmentation_from_assignment(PerMarker) reads, so a segmentation can be written out, adjusted
// by hand (as the paper did) and read back. Throws std::invalid_argument for a triangle_part of
// the wrong length or a marker index out of range.
std::vector<int> marker_parts(std::span<const std::array<int, 3>> triangles, std::span<const int> triangle_part,
                              int marker_count);

}  // namespace skinstream
