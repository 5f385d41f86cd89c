#!/bin/sh
# ROS: roscore & roslaunch imu_utils my_imu.launch & rosbag play -r 200 BAG (then wait). Usage: imu_utils.sh BAG [OUTDIR] [allan_imu_utils flags...]
. "$(dirname "$0")/lib.sh"
bag="$1"; shift
if [ $# -gt 0 ] && [ "${1#-}" = "$1" ]; then out="$1"; shift; else out="$(dirname "$bag")/$(basename "${bag%.*}")_allan_imu_utils"; fi
tool allan_imu_utils "$bag" --launch "$here/my_imu.launch" -o "$out" "$@"
