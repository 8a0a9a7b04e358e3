// RefinementReuse: a still tag keeps its refinement; a moved one, another
// tag, an old refinement or a cleared one does not.
#include <array>

#include <gtest/gtest.h>

#include "tracking/refinement_reuse.hpp"

namespace probelight {
namespace {

using tracking::RefinementReuse;
using tracking::RefinementReuseSettings;

std::array<glm::dvec2, 4> square(glm::dvec2 offset) {
  return {glm::dvec2(100, 100) + offset, glm::dvec2(200, 100) + offset, glm::dvec2(200, 200) + offset,
          glm::dvec2(100, 200) + offset};
}

TEST(RefinementReuse, KeepsItWhileEveryCornerStaysWithinTheShift) {
  RefinementReuse<int> reuse(RefinementReuseSettings{0.1, 30});
  EXPECT_EQ(reuse.reuse(7, square({0, 0})), nullptr) << "nothing stored yet";
  reuse.store(7, square({0, 0}), 42);
  const int* kept = reuse.reuse(7, square({0.05, -0.05}));
  ASSERT_NE(kept, nullptr);
  EXPECT_EQ(*kept, 42);
  // One corner alone past the shift is enough to refine.
  std::array<glm::dvec2, 4> one_moved = square({0, 0});
  one_moved[2] += glm::dvec2(0.0, 0.11);
  EXPECT_EQ(reuse.reuse(7, one_moved), nullptr);
  // Another tag id never takes it.
  EXPECT_EQ(reuse.reuse(8, square({0, 0})), nullptr);
}

TEST(RefinementReuse, TheShiftIsFromTheRefinedFrameSoADriftCannotPileUp) {
  RefinementReuse<int> reuse(RefinementReuseSettings{0.1, 1000});
  reuse.store(1, square({0, 0}), 1);
  // 0.03 px a frame: within 0.1 of the previous frame every time, but the
  // fourth frame is 0.12 px from the refined one.
  int reused = 0;
  for (int frame = 1; frame <= 10; ++frame)
    if (reuse.reuse(1, square({0.03 * frame, 0.0}))) ++reused;
  EXPECT_EQ(reused, 3);
}

TEST(RefinementReuse, AtMostMaxFramesInARowAndNeverWithAZeroShift) {
  RefinementReuse<int> reuse(RefinementReuseSettings{0.1, 3});
  reuse.store(1, square({0, 0}), 1);
  EXPECT_NE(reuse.reuse(1, square({0, 0})), nullptr);
  EXPECT_NE(reuse.reuse(1, square({0, 0})), nullptr);
  EXPECT_NE(reuse.reuse(1, square({0, 0})), nullptr);
  EXPECT_EQ(reuse.reuse(1, square({0, 0})), nullptr) << "the fourth frame refines again";
  reuse.store(1, square({0, 0}), 2);  // a new refinement starts the count over
  EXPECT_NE(reuse.reuse(1, square({0, 0})), nullptr);
  reuse.clear();
  EXPECT_EQ(reuse.reuse(1, square({0, 0})), nullptr);

  RefinementReuse<int> off(RefinementReuseSettings{0.0, 30});
  off.store(1, square({0, 0}), 1);
  EXPECT_EQ(off.reuse(1, square({0, 0})), nullptr) << "0 refines every frame";
}

}  // namespace
}  // namespace probelight
