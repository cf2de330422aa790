#pragma once

#include <array>
#include <string>
#include <vector>

#include "colorfree/perception/cnn/net.h"

namespace colorfree::cnn {

/// One of the nets shipped in perception/models (<stem>.cfg, <stem>.weights): the paper's five
/// with its Table 1 figures (NAO V5) beside them, then ours the paper has not (paper figures 0).
struct ShippedNet {
  const char* name;  ///< the paper's name
  const char* stem;  ///< file name without extension
  int input_side;
  std::array<const char*, 4> classes;  ///< label order; unused entries null
  int paper_parameters;
  double paper_time_ms;
  double paper_accuracy;

  std::vector<std::string> classNames() const {
    std::vector<std::string> out;
    for (const char* c : classes) {
      if (c != nullptr) out.emplace_back(c);
    }
    return out;
  }
  std::string cfgPath() const { return defaultModelDir() + "/" + stem + ".cfg"; }
  std::string weightsPath() const { return defaultModelDir() + "/" + stem + ".weights"; }
};

// One net a line.
// clang-format off
inline constexpr ShippedNet kShippedNets[] = {
    {"RobotNet", "robot_net", 24, {"none", "robot", nullptr, nullptr}, 884, 0.382, 0.969},
    {"BoostBallNet", "boost_ball_net", 12, {"none", "ball", nullptr, nullptr}, 125, 0.043, 0.965},
    {"BallNet", "ball_net", 26, {"none", "ball", nullptr, nullptr}, 444, 0.343, 0.984},
    {"OriBoostNet", "ori_boost_net", 12, {"unusable", "usable", nullptr, nullptr}, 246, 0.059, 0.962},
    {"OriNet", "ori_net", 24, {"front", "back", "side_left", "side_right"}, 657, 0.329, 0.984},
    {"SmearedBallNet", "smeared_ball_net", 26, {"none", "ball", nullptr, nullptr}, 0, 0, 0},
    {"RobotFeetNet", "robot_feet_net", 24, {"feet_right", "feet_lower", "feet_higher", nullptr}, 0, 0, 0},
    {"RobotBehindNet", "robot_behind_net", 24, {"none", "robot", nullptr, nullptr}, 0, 0, 0},
};
// clang-format on

}  // namespace colorfree::cnn
