// The ladder's gate (verification/common/record.hpp: rung_exit_status): a
// failing check fails its rung unless a documented known failure names it;
// a known-failure entry whose matching checks all pass fails the rung too,
// so that stale entries are removed and the check gates again.
#include <gtest/gtest.h>

#include "../../verification/common/record.hpp"

using rubble::verification::Check;
using rubble::verification::rung_exit_status;

namespace {
Check check(const std::string& name, double value) { return Check{name, value, 1.0, "<=", "test"}; }
}  // namespace

TEST(RungExitStatus, FailingChecksGateUnlessKnown) {
  EXPECT_EQ(rung_exit_status({check("a", 0.5), check("b", 0.5)}, {}), 0);
  EXPECT_EQ(rung_exit_status({check("a", 0.5), check("b", 2.0)}, {}), 1);
  EXPECT_EQ(rung_exit_status({check("a", 0.5), check("clumping at n = 25", 2.0)}, {"clumping"}), 0);
}

TEST(RungExitStatus, AKnownFailureStillFailingSomewhereIsNotStale) {
  // the same check at three resolutions: one passes, two fail
  EXPECT_EQ(rung_exit_status({check("clumping", 2.0), check("clumping", 0.5), check("clumping", 3.0)}, {"clumping"}), 0);
}

TEST(RungExitStatus, AKnownFailureThatPassesEverywhereIsStale) {
  EXPECT_EQ(rung_exit_status({check("clumping", 0.5), check("clumping", 0.7)}, {"clumping"}), 1);
  // an entry that matches no check at all (a part not run) is not judged
  EXPECT_EQ(rung_exit_status({check("a", 0.5)}, {"clumping"}), 0);
}

// Every record names the run that made it (write_record appends it).
TEST(RecordMetadata, WithAppendsKeysToAnObject) {
  using rubble::verification::Json;
  EXPECT_EQ(Json::object({{"a", 1}}).with({{"b", "x"}}).str(), "{\"a\": 1, \"b\": \"x\"}");
  EXPECT_EQ(Json::object({}).with({{"b", 2}}).str(), "{\"b\": 2}");
  EXPECT_EQ(Json::object({{"a", 1}}).with({}).str(), "{\"a\": 1}");
  EXPECT_THROW(Json(1.0).with({{"b", 2}}), std::logic_error);
}

TEST(RecordMetadata, RunMetadataNamesBackendPrecisionAndCommit) {
  using rubble::verification::Json;
  const std::string s = Json::object(rubble::verification::run_metadata("cuda")).str();
  EXPECT_NE(s.find("\"backend\": \"cuda\""), std::string::npos) << s;
  EXPECT_NE(s.find(sizeof(rubble::Real) == 8 ? "\"precision\": \"double\"" : "\"precision\": \"float\""),
            std::string::npos)
      << s;
  EXPECT_NE(s.find("\"commit\": \""), std::string::npos) << s;
}

TEST(RecordMetadata, NumbersAreTheShortestTextThatReadsBackExactly) {
  using rubble::verification::exact_number;
  EXPECT_EQ(exact_number(45 + 19.8 / 2), "54.9");
  EXPECT_EQ(exact_number(0.1), "0.1");
  EXPECT_EQ(exact_number(1e-300), "1e-300");
  for (double v : {0.44234849799999998, 1.0 / 3.0, 2.0 / 3.0 * 1e-7, 6.02214076e23, -0.0})
    EXPECT_EQ(std::stod(exact_number(v)), v) << exact_number(v);
  EXPECT_EQ(rubble::verification::Json(0.25).str(), "0.25");
  EXPECT_EQ(rubble::verification::Json(std::nan("")).str(), "null");
}
