// bench_ball's baseline: the ball proposer before issue 6's speed work (see the .cpp).
#pragma once

#include <vector>

#include "colorfree/perception/ball_proposer.h"

namespace colorfree {
namespace bench {

std::vector<BallProposal> referenceBallProposals(const BallProposerParams& p, const GrayView& image,
                                                 const CameraModel& camera, const IgnoreMask& ignore,
                                                 const ContrastRegions& regions,
                                                 const std::vector<RobotPercept>* robots);

}  // namespace bench
}  // namespace colorfree
