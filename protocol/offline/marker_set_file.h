#pragma once
// Marker-set definition files (JSON; the format is written down in docs/marker-sets.md, the
// shipped sets are in config/marker_sets/): one set per file,
//   { "name": "...", "source": "...", "notes": "...",          notes optional
//     "markers": [
//       { "name": "LELB", "aliases": ["..."], "description": "...",          a point entry
//         "bone": "lowerarm01.L", "along": 0.0, "direction": [-1, 0, 0], "radius_mm": 30 },
//       { "pattern": "thigh_L_*", "description": "...",                      a region entry
//         "bones": ["upperleg01.L", "upperleg02.L"], "side": "front" } ] }
// Optional fields: aliases ([]), description (""), along (0.5), radius_mm (30), side ("any").
// The direction is normalised on reading. Everything else is checked as core/fitting/marker_set.h
// validate() says, and a file may hold nothing it does not know: an unknown or repeated key, a
// value of the wrong JSON type, a non-finite number are refused too.
#include <string>
#include <vector>

#include "core/fitting/marker_set.h"

namespace skinstream {

// Throws FileError, one line naming the file and the entry, e.g.
// "pig.json: marker set 'Vicon Plug-in Gait' entry 12 (LELB): direction must be 3 numbers".
MarkerSet read_marker_set(const std::string& path);

// Every *.json file in `folder`, in file-name order. Throws FileError for a folder that cannot
// be read or holds no *.json file, for any bad file (as above), and for two files that define
// sets of the same name (case ignored).
std::vector<MarkerSet> read_marker_sets(const std::string& folder);

}  // namespace skinstream
