// Every expectation in the shipped scenarios names a metric results.json has, so `colorfree run`
// on them cannot stop with "unknown metric".
#include <gtest/gtest.h>

#include <filesystem>

#include "colorfree/groundtruth/results.h"
#include "colorfree/sim/scenario.h"
#include "test_support.h"

namespace colorfree {
namespace {

TEST(ShippedScenarios, ExpectationsNameKnownMetrics) {
  int scenarios = 0;
  for (const auto& path : test::shippedScenarioFiles()) {
    const sim::Scenario s = sim::Scenario::load(path.string());
    ++scenarios;
    for (const auto& e : s.expect) {
      const std::string origin = path.string() + ":" + std::to_string(e.line);
      EXPECT_NO_THROW(validateExpectations({parseExpectation(e.text, origin)}, origin))
          << origin << ": " << e.text;
    }
  }
  EXPECT_GT(scenarios, 0);
}

}  // namespace
}  // namespace colorfree
