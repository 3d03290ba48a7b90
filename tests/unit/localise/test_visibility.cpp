// Free-space evidence: a line of sight through a mapped wall is blocked, one in the open is
// not, and neither is one that ends on (or grazes) the surface its point lies on.
#include <gtest/gtest.h>

#include "likelihood_grid.h"
#include "visibility.h"

namespace mrvs::localise {
namespace {

/// A map of one wall: the plane x = 2, y and z in [-2, 2].
LikelihoodPyramid wall_grid() {
  std::vector<Eigen::Vector3f> pts;
  for (float y = -2.0f; y <= 2.0f; y += 0.05f) {
    for (float z = -2.0f; z <= 2.0f; z += 0.05f) pts.emplace_back(2.0f, y, z);
  }
  return LikelihoodPyramid::build(
      pts, Eigen::AlignedBox3d(Eigen::Vector3d::Constant(-3), Eigen::Vector3d::Constant(4)), 0.1, 1, 1.0);
}

TEST(Visibility, ALineThroughAWallIsBlockedOneInTheOpenIsNot) {
  const LikelihoodPyramid g = wall_grid();
  const std::vector<SightLine> through{{Eigen::Vector3d::Zero(), Eigen::Vector3d(3.0, 0.5, 0.0)}};
  const std::vector<SightLine> open{{Eigen::Vector3d::Zero(), Eigen::Vector3d(1.5, 0.5, 0.0)}};
  const std::vector<SightLine> on_wall{{Eigen::Vector3d::Zero(), Eigen::Vector3d(2.0, 0.5, 0.3)}};
  EXPECT_EQ(blocked_share(g, through, 0.0, Eigen::Vector3d::Zero(), 0.2, 0.15, 0.0), 1.0);
  EXPECT_EQ(blocked_share(g, open, 0.0, Eigen::Vector3d::Zero(), 0.2, 0.15, 0.0), 0.0);
  EXPECT_EQ(blocked_share(g, on_wall, 0.0, Eigen::Vector3d::Zero(), 0.2, 0.15, 0.0), 0.0);
  // The pose turns the lines: a half turn puts the point behind the viewpoint, away from the wall.
  EXPECT_EQ(blocked_share(g, through, M_PI, Eigen::Vector3d::Zero(), 0.2, 0.15, 0.0), 0.0);
  // ... and the anchor moves them: from x = 2.5 the point (x = 5.5) is in the open beyond the wall.
  EXPECT_EQ(blocked_share(g, through, 0.0, Eigen::Vector3d(2.5, 0.0, 0.0), 0.2, 0.15, 0.0), 0.0);
  // Half of two lines.
  std::vector<SightLine> both = through;
  both.push_back(open.front());
  EXPECT_EQ(blocked_share(g, both, 0.0, Eigen::Vector3d::Zero(), 0.2, 0.15, 0.0), 0.5);
  EXPECT_EQ(blocked_share(g, {}, 0.0, Eigen::Vector3d::Zero(), 0.2, 0.15, 0.0), 0.0);
}

TEST(Visibility, AGrazingLineIsNotBlockedByItsOwnSurface) {
  const LikelihoodPyramid g = wall_grid();
  // From (2.05, -1.5, 0) along the wall to a point on it 3 m away: in the wall's cells
  // all the way. The margin's share of the length keeps it clear; without it, it is blocked.
  const std::vector<SightLine> grazing{{Eigen::Vector3d(2.05, -1.5, 0.0), Eigen::Vector3d(2.02, 1.5, 0.0)}};
  EXPECT_EQ(blocked_share(g, grazing, 0.0, Eigen::Vector3d::Zero(), 0.2, 0.15, 0.0), 1.0);
  EXPECT_EQ(blocked_share(g, grazing, 0.0, Eigen::Vector3d::Zero(), 0.2, 0.15, 1.0), 0.0);
}

}  // namespace
}  // namespace mrvs::localise
