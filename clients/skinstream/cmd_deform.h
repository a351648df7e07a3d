#pragma once
// skinstream deform: a filled capture -> the deforming detailed mesh (section 5.3), as the daemon
// computes it per frame, written as per-frame meshes and a point cache.
//   skinstream deform --subject S.sksubj --capture FILLED.c3d --out DIR [--format ply|obj|pc2|none]
//                     [--mode full|quadratic|rigid-rbf|rigid] [--fill] [--no-pc2]
// Writes DIR/frame_<frame number, 6 digits>.<format> for ply and obj (frame number = the
// capture's first frame + index, as the replay server numbers frames), DIR/deformed.pc2 (every
// frame; format pc2 or none: the point cache alone) and DIR/rest.obj (the registered reference
// mesh whose vertex order the point cache follows).
#include <cstdio>
#include <string>

namespace skinstream::cli {

struct DeformOptions {
  std::string subject_path;  // built with build-subject --mesh
  std::string capture_path;  // filled, unless `fill`
  std::string out_dir;
  std::string format = "ply";  // ply or obj per frame; pc2 or none: the point cache only
  std::string mode = "full";   // full (quadratic + RBF), quadratic, rigid-rbf or rigid
  bool fill = false;           // relabel and fill the capture online first (as the daemon does)
  bool no_pc2 = false;         // no point cache
};

// Writes the meshes and prints a JSON summary to `out`. Returns 2 when frames had missing
// markers (they repeat the previous shape; said on stderr), else 0. Throws on bad files or
// options that would write nothing.
int run_deform(const DeformOptions& options, std::FILE* out);

}  // namespace skinstream::cli
