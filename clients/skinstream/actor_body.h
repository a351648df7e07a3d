#pragma once
// The body an actor's subject is built on, from the mesh given on the command line: the body
// template (a MakeHuman body OBJ with its skeleton and weights beside it) as it is, or a user's
// own scan made a skinned body through the template (core/fitting/scan_body.h). Either way the
// mesh is first checked to be a body in the unit and axes its flags say (mesh_frame.h). Shared
// by build-subject and eval-actor.
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/body/body.h"
#include "core/fitting/actor_fit.h"
#include "core/fitting/marker_priors.h"
#include "core/fitting/mesh_frame.h"
#include "core/fitting/scan_body.h"
#include "core/fitting/template_segments.h"

namespace skinstream::cli {

class ActorBody {
 public:
  // mesh_path: the template's body OBJ, or a scan (.obj/.ply); template_dir: the template used for
  // a scan. Throws FileError or std::invalid_argument (one line): a mesh that is not a body, a
  // flag the body contradicts.
  ActorBody(const std::string& mesh_path, const MeshFrameOptions& flags, const std::string& template_dir);
  ActorBody(const ActorBody&) = delete;
  ActorBody& operator=(const ActorBody&) = delete;

  bool is_scan() const { return scan_.has_value(); }
  const FitBody& fit_body() const { return fit_body_; }
  const TemplateSegments& segments() const { return segments_; }
  const ScanBody* scan() const { return scan_ ? &*scan_ : nullptr; }
  const MeshFrame& frame() const { return frame_; }
  // What the marker sets say of these labels, on this body (carried to the scan for a scan).
  MarkerPriors priors(std::span<const std::string> labels, std::span<const MarkerSet> sets) const;

 private:
  Body template_;
  TemplateSegments segments_;
  MeshFrame frame_;
  std::optional<ScanBody> scan_;
  FitBody fit_body_;
};

// Whether the mesh is the body template: its skeleton, weights and base mesh beside it.
bool is_body_template(const std::string& mesh_path);

}  // namespace skinstream::cli
