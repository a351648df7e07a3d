#pragma once
// skinstream synth: a synthetic dense-marker capture (Park & Hodgins style, ~350 skin markers,
// 12-camera occlusion, broken trajectories) from the CC0 MakeHuman body, with its truth.
//
//   skinstream synth --motion rom --seconds 20 --seed 7 --markers 350 --out take.c3d
//                    --truth take_truth.c3d [--mesh-out-every 10 meshes/] [--subdivided] [--stats]
//                    [--lookahead L]
//
// The body is read from --body DIR, else default_body_dir() (default_paths.h). Meshes are binary
// PLY, DIR/mesh_<frame>.ply (frame index from 0, millimetres, Z up, the same vertex order every
// frame).
#include <cstdio>
#include <string>

#include "core/synth/synth_capture.h"

namespace skinstream::cli {

struct SynthOptions {
  synth::SynthOptions take;  // motion, seconds, seed, markers, subdivided, deform
  std::string out_path;      // the broken capture as delivered by the capture system
  std::string truth_path;    // when set: every labelled marker every frame, no noise
  int mesh_every = 0;        // > 0: the truth mesh of every N-th frame as PLY into mesh_dir
  std::string mesh_dir;
  std::string body_dir;  // the MakeHuman files; empty: default_body_dir()
  bool stats = false;    // the counts as JSON, and skinstream's relabelling and filling judged
  double train_seconds = 20.0;  // with stats: the range-of-motion training take
  int lookahead = 0;            // with stats: frames of lookahead for the fill
};

// Writes the captures (and meshes) and prints what was written, or the statistics as JSON, to
// `out`; returns the exit code. Throws on a body that cannot be read or a file not written.
int run_synth(const SynthOptions& options, std::FILE* out);

}  // namespace skinstream::cli
