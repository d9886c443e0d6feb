# The profile-guided build's training run (CMakeLists.txt, RBCD_PGO):
#   cmake -DBIN=<instrumented bin/> -DPROFILE=<counts dir> -DWORK=<scratch dir>
#         -DSTAMP=<file> -P pgo_train.cmake
# What it runs decides which code GCC lays out as hot: the paths users spend
# their time on, on inputs of their kind but not rbcd-bench's (other seeds,
# other sizes), so that the benchmark measures the build, not its training.
#   - a trace whose fragments come in per-object bursts (the sorter's loops)
#     and one whose objects interleave (its all-slots path), each read on a
#     thread of its own (one process) and inline (as a --jobs worker reads),
#     with collisions, stats and per-frame stats written;
#   - the embedded default scene (the scene rasterizer), with its outputs.
# The counts of an earlier training are removed first: GCC would add the new
# counts to them, or refuse them when the code they counted has changed.
foreach(v BIN PROFILE WORK STAMP)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "pgo_train.cmake: -D${v}= is required")
  endif()
endforeach()

file(REMOVE_RECURSE ${PROFILE} ${WORK})
file(MAKE_DIRECTORY ${PROFILE} ${WORK})

function(run)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY ${WORK} RESULT_VARIABLE rc OUTPUT_QUIET
                  ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    list(JOIN ARGN " " cmd)
    message(FATAL_ERROR "profile-guided build: the training run failed (${rc}): ${cmd}\n${err}")
  endif()
endfunction()

set(ENV{SYSTEMC_DISABLE_COPYRIGHT_MESSAGE} 1)
set(outputs --collisions c.txt --stats s.json --frame-stats f.jsonl)
run(${BIN}/gen_busy_trace bursty.rbt 1200000 4 101)
run(${BIN}/gen_busy_trace interleaved.rbt 1200000 4 202 --interleaved)
foreach(trace bursty.rbt interleaved.rbt)
  run(${BIN}/rbcd-sim --trace ${trace} -q ${outputs})
  run(${BIN}/rbcd-sim --trace ${trace} --threads 1 -q ${outputs})
endforeach()
run(${BIN}/rbcd-sim -q ${outputs})

file(GLOB counts ${PROFILE}/*.gcda)
if(NOT counts)
  message(FATAL_ERROR "profile-guided build: the training wrote no counts into ${PROFILE}")
endif()
file(REMOVE_RECURSE ${WORK})
file(TOUCH ${STAMP})
