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
