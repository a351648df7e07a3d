#pragma once
// The XML QTM answers `GetParameters General 3D` with (the body of an XML packet):
//
//   <QTM_Parameters_Ver_1.19>
//     <General><Frequency>120</Frequency>...</General>
//     <The_3D>
//       <AxisUpwards>+Z</AxisUpwards> <CalibrationTime>...</CalibrationTime>
//       <Labels>2</Labels>
//       <Label><Name>Actor1_LFHD</Name><RGBColor>255</RGBColor></Label> ...
//     </The_3D>
//   </QTM_Parameters_Ver_1.19>
//
// The Label elements give the order of the positions in every 3D component. Parsing is by a real
// XML parser (expat); a document that is not well formed, whose Labels count disagrees with its
// Label elements, with an element's text over 1 kB or more than 100,000 labels is refused with a
// one-line reason.

#include <string>
#include <string_view>
#include <vector>

namespace skinstream::qtm {

struct Parameters {
  double frequency_hz = 0.0;  // General/Frequency; 0 when the document has none
  double capture_time_s = 0.0;
  bool has_3d = false;
  std::string axis_upwards = "+Z";
  std::vector<std::string> labels;
};

std::string write_parameters_xml(const Parameters& parameters, int minor_version);
bool parse_parameters_xml(std::string_view xml, Parameters& out, std::string& out_error);

}  // namespace skinstream::qtm
