#!/bin/sh
# ROS: rosrun vio_data_simulation vio_data_simulation_node (writes imu.bag: 4 h static IMU at 200 Hz). Usage: simulate.sh [OUT.bag] [sim bag flags...]
. "$(dirname "$0")/lib.sh"
out="${1:-imu.bag}"; [ $# -gt 0 ] && shift
tool sim bag --output "$out" "$@"
