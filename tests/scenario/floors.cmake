# Regression floors for CI (see CMakeLists.txt): colorfree_floor_test(name scenario frames_per_case
# "metric op floor" ...). Each floor: the value measured on this code (in the comment) less a small
# margin. The scenario files keep the issues' targets; `colorfree run SCENARIO` checks those.

# Ball, game-like set (12 cases x 4 frames, 24 balls to detect). Measured: proposal recall 1.000,
# detection 1.000, false positives 0.000 per frame (the issue's targets are met; one miss or one
# false positive is the margin).
colorfree_floor_test(ball_game_floor ball_game.yaml 4
  "ball.proposal_recall >= 0.95" "ball.detection_rate >= 0.95" "ball.false_positives_per_frame <= 0.03")

# Ball, hard set (4 cases x 6 frames, 8 balls to detect). Measured: proposal recall 1.000,
# detection 1.000, false positives 0.000 per frame (the smeared ball's centre from its vote ridge;
# before: detection 0.875; one miss is the margin).
colorfree_floor_test(ball_hard_floor ball_hard.yaml 6
  "ball.proposal_recall >= 0.87" "ball.detection_rate >= 0.87")

# Robots, CI-sized detection set (4 cases x 4 frames). Measured: proposal recall 0.875, detection
# 0.875, false positives 0.125 per frame (RobotNet retrained with robot_near_views_train on the
# proposer whose feet include their dark lower part; before: detection 0.688; before robotprop:
# recall 0.812, detection 0.688, 0.062 false positives per frame). RobotNet retrained with the far
# and near training scenes (robot5): detection 0.812, no false positive.
colorfree_floor_test(robot_detection_floor ci/robot_detection_ci.yaml 4
  "robot.proposal_recall >= 0.81" "robot.detection_rate >= 0.81" "robot.false_positives_per_frame <= 0.07")

# Robot orientation, CI-sized static set (8 headings x 3 frames, 1.2 m). Measured: filtered
# perceived 1.000, semi-perceived 0, false positives 0 (before OriNet saw a side's facing:
# 0.625 / 0.25 / 0).
colorfree_floor_test(orientation_static_floor ci/orientation_static_ci.yaml 3
  "orientation.filtered.perceived >= 0.95" "orientation.filtered.false_positive <= 0.05")

# Robot orientation, CI-sized dynamic set (8 headings x 4 frames, walking at 12 cm/s). Measured:
# filtered perceived 1.000, semi-perceived 0, false positives 0 (orient2: the shadow test and the
# retrained orientation nets; before: 0.750 / 0 / 0, and 0.500 / 0.312 / 0.125 before that);
# merged with robot3's proposer and RobotNet 0.969 / 0 / 0 (RobotNet misses one robot-frame);
# RobotNet retrained with the far and near training scenes (robot5): 1.000 / 0 / 0.
colorfree_floor_test(orientation_dynamic_floor ci/orientation_dynamic_ci.yaml 4
  "orientation.filtered.perceived >= 0.95" "orientation.filtered.false_positive <= 0.04")

# Ball under sensor noise (the camera-noise sweep, sigma 0-40 gray levels, 7 cases x 3 frames).
# Measured: proposal recall 1.000, detection 0.952, false positives 0.048 per frame (the proposer's
# responses net of the frame's noise; before: detection 0.714, nothing at sigma 25 and 40, 0.095 false
# positives per frame). One more miss or false positive is the margin.
colorfree_floor_test(ball_noise_floor sweeps/camera_noise.yaml 3
  "ball.detection_rate >= 0.90" "ball.false_positives_per_frame <= 0.10")

# Robots beside the ball at the observer's feet (the hard set's 12 cases x 8 frames, 60 robot-frames
# to detect). Measured: detection 0.750, false positives 0.021 per frame (robot19: near robots cut
# by the lower border proposed, and boxes at a nearer robot's knees held to the bar behind a robot;
# before: 0.617 and 0.083). Two robot-frames and two false positives are the margin.
colorfree_floor_test(robot_hard_feet_floor ball_hard_feet.yaml 8
  "robot.detection_rate >= 0.72" "robot.false_positives_per_frame <= 0.05")

# Ball and robot behind a soft lens in a dim hall (the lens-defocus sweep, point spread 0-4 px, 5
# cases x 4 frames, 20 balls and 20 robot-frames to detect). Measured: ball 0.750, robot 0.950, no
# false positive (session 19: BallNet's sharpened look at a rejected patch, without it ball 0.650;
# the high-contrast threshold that follows the light, without it robot 0.500; session 31: a sparse
# frame's lower bar, without it robot 0.900). One miss is the margin.
colorfree_floor_test(defocus_floor sweeps/lens_defocus.yaml 4
  "ball.detection_rate >= 0.70" "ball.false_positives_per_frame <= 0.05"
  "robot.detection_rate >= 0.90" "robot.false_positives_per_frame <= 0.05")

# Ball behind a soft lens with the head sweeping (ball_hard_soft: 6 cases x 8 frames, 48 balls).
# Measured: detection 1.000, no false positive, proposal recall 1.000 (session 37: the deblurred
# look, BallNet on the patch with the camera's smear taken back; without it detection 0.875, the six
# balls of frame 4 lost). One miss is the margin.
colorfree_floor_test(ball_soft_floor ball_hard_soft.yaml 8
  "ball.detection_rate >= 0.97" "ball.false_positives_per_frame <= 0.03")

# Ball smeared by the head's sweep over a 20 ms exposure with a rolling shutter, by the penalty mark
# and the goal-area line (ball_hard_marks: 6 cases x 8 frames, 48 balls). Measured: detection 0.854,
# proposal recall 0.938, no false positive (session 40: the proposals' surround widened along the
# camera's smear; before it 0.833 and 0.917). One miss is the margin.
colorfree_floor_test(ball_marks_floor ball_hard_marks.yaml 8
  "ball.detection_rate >= 0.83" "ball.proposal_recall >= 0.91" "ball.false_positives_per_frame <= 0.03")

# Ball behind three robots, beside their bodies, between them or partly hidden (ball_hard_behind: 6
# cases x 12 frames, 54 balls). Measured: detection 0.833, proposal recall 0.833, no false positive
# (session 42: a robot's body damps the ball responses only in the middle 0.8 of its box, to 0.7 of
# them; with the whole box damped to 0.5, as before, 0.556). One miss is the margin.
colorfree_floor_test(ball_behind_floor ball_hard_behind.yaml 12
  "ball.detection_rate >= 0.81" "ball.proposal_recall >= 0.81" "ball.false_positives_per_frame <= 0.03")

# Four robots, some overlapping, normal and uneven light (robots_overlapping: 2 cases x 10 frames,
# 52 robot-frames). Measured: detection 0.904 (session 40: rejected boxes' feet searched by
# RobotFeetNet; before it 0.885), false positives 0 per frame (session 43: RobotBehindNet's veto;
# before it 0.050). One miss and one false positive are the margin.
colorfree_floor_test(robots_overlapping_floor robots/robots_overlapping.yaml 10
  "robot.detection_rate >= 0.88" "robot.false_positives_per_frame <= 0.05")

# Robots 0.5-6 m straight ahead (the robot-distance sweep, 8 cases x 2 frames). Measured (session
# 41): detection 1.000; before the proposals from the lowest row, the robot 0.5 m away (the lower
# border across its body) was missed: 0.875. False positives 0 per frame since session 43's
# RobotBehindNet veto (0.250 before, at 1.5 and 2 m); one false positive is the margin.
colorfree_floor_test(robot_distance_floor sweeps/robot_distance.yaml 2
  "robot.detection_rate >= 0.93" "robot.false_positives_per_frame <= 0.07")

# Robot orientation, the static test with the robot standing on the penalty area's front line
# (16 headings x 6 presets x 1 frame). Measured: filtered perceived 0.812, false 0.094 (session 44's
# field lines keep the line under the robot's feet; with the code before, the whole set at 3 frames
# a case gave 0.660 / 0.205). Three robot-frames are the margin.
colorfree_floor_test(orientation_lines_floor orientation_static_lines.yaml 1
  "orientation.filtered.perceived >= 0.78" "orientation.filtered.false_positive <= 0.13")

# Robot orientation, the static test with the robot standing on the centre circle (16 headings x 6
# presets x 1 frame; session 47). Measured: filtered perceived 0.969, false 0.010 (0.958 / 0.010
# without session 47's sole rule). Three robot-frames are the margin.
colorfree_floor_test(orientation_circle_floor orientation_static_circle.yaml 1
  "orientation.filtered.perceived >= 0.938" "orientation.filtered.false_positive <= 0.042")
