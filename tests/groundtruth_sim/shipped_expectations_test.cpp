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
  for (const auto& entry : std::filesystem::recursive_directory_iterator(test::sourceDir() + "/scenes")) {
    // scenes/bench.yaml is the bench's list of scenarios, not a scenario.
    if (entry.path().extension() != ".yaml" || entry.path().filename() == "bench.yaml") continue;
    const sim::Scenario s = sim::Scenario::load(entry.path().string());
    ++scenarios;
    for (const auto& e : s.expect) {
      const std::string origin = entry.path().string() + ":" + std::to_string(e.line);
      EXPECT_NO_THROW(validateExpectations({parseExpectation(e.text, origin)}, origin))
          << origin << ": " << e.text;
    }
  }
  EXPECT_GT(scenarios, 0);
}

}  // namespace
}  // namespace colorfree
