#include "server/control/control_routes.h"

#include <gtest/gtest.h>

#include <set>

namespace skinstream::server {
namespace {

TEST(ControlRoutes, PatternsMatchWholeSegmentsOnly) {
  ControlPathParameters parameters;
  EXPECT_TRUE(control_path_matches("/takes", "/takes", parameters));
  EXPECT_TRUE(control_path_matches("/takes/stop", "/takes/stop", parameters));
  EXPECT_FALSE(control_path_matches("/takes", "/takes/", parameters));
  EXPECT_FALSE(control_path_matches("/takes", "/takesx", parameters));
  EXPECT_FALSE(control_path_matches("/takes/stop", "/takes", parameters));
  EXPECT_FALSE(control_path_matches("/takes", "/takes/stop", parameters));
  EXPECT_FALSE(control_path_matches("/takes", "", parameters));
  EXPECT_FALSE(control_path_matches("/takes", "takes", parameters));
}

TEST(ControlRoutes, ANamedSegmentIsHandedOverAndMustNotBeEmpty) {
  ControlPathParameters parameters;
  ASSERT_TRUE(
      control_path_matches("/subjects/{name}/calibration", "/subjects/Actor1/calibration", parameters));
  ASSERT_EQ(parameters.size(), 1u);
  EXPECT_EQ(parameters[0].first, "name");
  EXPECT_EQ(parameters[0].second, "Actor1");
  EXPECT_FALSE(control_path_matches("/subjects/{name}/calibration", "/subjects//calibration", parameters));
  EXPECT_FALSE(control_path_matches("/subjects/{name}", "/subjects/a/b", parameters));
}

TEST(ControlRoutes, ControlPathsAreTheRoutesFirstSegments) {
  EXPECT_TRUE(is_control_path("/takes"));
  EXPECT_TRUE(is_control_path("/takes/stop"));
  EXPECT_TRUE(is_control_path("/takes/anything"));
  EXPECT_FALSE(is_control_path("/"));
  EXPECT_FALSE(is_control_path("/health"));
  EXPECT_FALSE(is_control_path("/takes.html"));
  EXPECT_FALSE(is_control_path(""));
}

TEST(ControlRoutes, EveryMethodAndPatternIsRoutedOnce) {
  std::set<std::pair<std::string_view, std::string_view>> seen;
  for (const ControlRoute& route : control_routes())
    EXPECT_TRUE(seen.insert({route.method, route.pattern}).second) << route.method << " " << route.pattern;
  EXPECT_FALSE(seen.empty());
}

}  // namespace
}  // namespace skinstream::server
