#!/bin/sh
# MATLAB: SCRIPT_allan_matparallel.m then SCRIPT_process_results.m on the .mat (or straight from the bag). Usage: kalibr_analyse.sh FILE.mat|BAG [allan_kalibr flags...]
. "$(dirname "$0")/lib.sh"
tool allan_kalibr "$@"
