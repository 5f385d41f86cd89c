#!/bin/sh
# ROS: rosrun bagconvert bagconvert BAG TOPIC (writes BAG's stem .mat beside it). Usage: kalibr_convert.sh BAG [TOPIC]
. "$(dirname "$0")/lib.sh"
if [ $# -gt 1 ]; then tool bag2mat "$1" "$2"; else tool bag2mat "$1"; fi
