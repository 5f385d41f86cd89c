#!/bin/sh
# ROS: roscore & roslaunch imu_utils my_imu.launch & rosbag play -r 200 BAG (then wait). Usage: imu_utils.sh BAG [OUTDIR] [allan_imu_utils flags...]
bag="$1"; out="${2:-.}"; shift; [ $# -gt 0 ] && shift; exec allan_imu_utils "$bag" --launch "$(dirname "$0")/my_imu.launch" --data-save-path "$out" "$@"
