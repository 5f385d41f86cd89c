#!/bin/sh
# ROS: rosrun bagconvert bagconvert BAG TOPIC (writes BAG's stem .mat beside it). Usage: kalibr_convert.sh BAG [TOPIC]
exec bag2mat "$1" "${2:-imu}"
