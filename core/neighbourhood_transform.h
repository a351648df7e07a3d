#pragma once
// The rigid transform of eq. 2 for one marker: local reference frame -> world, fitted to the
// marker's one-ring at the given positions. Its translation is the rigid estimate of the marker.

#include <span>

#include "core/absolute_orientation.h"
#include "core/subject_model.h"

namespace skinstream {

// Uses ring members whose position is finite (and, when `usable` is not empty, usable[j] != 0).
// Returns false when fewer than three are usable. Allocation-free.
bool neighbourhood_transform(const SubjectModel& model, int marker, std::span<const Vec3> positions,
                             std::span<const char> usable, RigidTransform& out);

}  // namespace skinstream
