#include "colorfree/sim/mujoco_errors.h"

#include <cstdio>
#include <mujoco/mujoco.h>
#include <string>

#include "colorfree/perception/error.h"

namespace colorfree {

namespace {
void onError(const char* msg) { throw Error(std::string("MuJoCo: ") + msg); }
void onWarning(const char* msg) { std::fprintf(stderr, "MuJoCo warning: %s\n", msg); }
}  // namespace

void installMujocoErrorHandlers() {
  mju_user_error = onError;
  mju_user_warning = onWarning;
}

}  // namespace colorfree
