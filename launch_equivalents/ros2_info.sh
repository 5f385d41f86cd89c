#!/bin/sh
# ROS 2: ros2 bag info BAGDIR (any ROS 1 or ROS 2 bag, .mcap or .db3 here). Usage: ros2_info.sh BAG
. "$(dirname "$0")/lib.sh"
tool bag2mat info "$@"
