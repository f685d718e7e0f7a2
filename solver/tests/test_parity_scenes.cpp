// The backend-parity test's scenes (gpu/parity_scenes.hpp), built and
// stepped on the CPU (issue #15 item 1): each is a valid scene that runs
// its 1 and 100 steps of exactly dt, so an invalid scene is caught here by
// .ci/run, not on a rare GPU host. One test case per scene.
#include <gtest/gtest.h>

#include <string>

#include "gpu/parity_scenes.hpp"

using namespace rubble;

class ParityScenes : public ::testing::TestWithParam<rubble::parity::ParityScene> {};

TEST_P(ParityScenes, BuildAndStepOnTheCpu) {
  const auto& sc = GetParam();
  for (const int steps : {1, 100}) {
    const FinalState fs = rubble::parity::run_on(sc.make(steps), Backend::Cpu);
    EXPECT_EQ(fs.steps, steps) << sc.name;
    EXPECT_GT(fs.m.size(), 0u) << sc.name;
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, ParityScenes, ::testing::ValuesIn(rubble::parity::scenes()),
                         [](const ::testing::TestParamInfo<rubble::parity::ParityScene>& i) {
                           return std::string(i.param.name);
                         });

// The Coulomb variant does carry Coulomb walls (its --set keys took effect).
TEST(ParityScenesCoulomb, TheFloorAndTheBackWallAreCoulomb) {
  const Scene s = rubble::parity::granular_column_coulomb(1);
  ASSERT_GE(s.bodies.size(), 3u);
  for (int b : {1, 2}) {
    EXPECT_EQ(s.bodies[b].wall_slip, WallSlip::Coulomb) << b;
    EXPECT_DOUBLE_EQ(s.bodies[b].wall_friction, 0.36) << b;
  }
  EXPECT_DOUBLE_EQ(s.bodies[1].wall_normal[1], 1.0);
  EXPECT_DOUBLE_EQ(s.bodies[2].wall_normal[0], 1.0);
}
