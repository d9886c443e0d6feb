# The profile-guided build's training run (CMakeLists.txt, RBCD_PGO):
#   cmake -DBIN=<instrumented bin/> -DPROFILE=<counts dir> -DWORK=<scratch dir>
#         -DSTAMP=<file> -P pgo_train.cmake
# What it runs decides which code GCC lays out as hot: the paths users spend
# their time on, on inputs of their kind but not rbcd-bench's (other seeds,
# other sizes), so that the benchmark measures the build, not its training.
#   - a trace whose fragments come in per-object bursts (the sorter's loops)
#     and one whose objects interleave (its all-slots path), with
#     collisions, stats and per-frame stats written;
#   - the embedded default scene (the scene rasterizer), with its outputs.
# The same counts every time, so that two builds of one source tree are the
# same program: on one thread (--threads 1, as a --jobs worker runs), since
# the hand-off between a reader thread and the model waits a varying number
# of times; and without address randomisation (setarch -R, where it is
# allowed), since GCC also records pointers' low bits (for alignment).
# The counts of an earlier training are removed first: GCC would add the new
# counts to them, or refuse them when the code they counted has changed.
foreach(v BIN PROFILE WORK STAMP)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "pgo_train.cmake: -D${v}= is required")
  endif()
endforeach()

file(REMOVE_RECURSE ${PROFILE} ${WORK})
file(MAKE_DIRECTORY ${PROFILE} ${WORK})

find_program(SETARCH setarch)
set(fixed_layout)
if(SETARCH)
  execute_process(COMMAND ${SETARCH} -R true RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
  if(rc EQUAL 0)
    set(fixed_layout ${SETARCH} -R)
  endif()
endif()

# Bounded: an instrumented run takes seconds; one that hangs must not hang the build.
function(run)
  execute_process(COMMAND ${fixed_layout} ${ARGN} WORKING_DIRECTORY ${WORK} RESULT_VARIABLE rc OUTPUT_QUIET
                  ERROR_VARIABLE err TIMEOUT 600)
  if(NOT rc EQUAL 0)
    list(JOIN ARGN " " cmd)
    message(FATAL_ERROR "profile-guided build: the training run failed (${rc}): ${cmd}\n${err}"
                        "(configure with -DRBCD_PGO=OFF to build without the profile)")
  endif()
endfunction()

set(ENV{SYSTEMC_DISABLE_COPYRIGHT_MESSAGE} 1)
set(outputs --collisions c.txt --stats s.json --frame-stats f.jsonl)
run(${BIN}/gen_busy_trace bursty.rbt 1200000 4 101)
run(${BIN}/gen_busy_trace interleaved.rbt 1200000 4 202 --interleaved)
foreach(trace bursty.rbt interleaved.rbt)
  run(${BIN}/rbcd-sim --trace ${trace} --threads 1 -q ${outputs})
endforeach()
run(${BIN}/rbcd-sim --threads 1 -q ${outputs})

# rbcd-sim's own counts, named as the build that uses them looks for them
# (relative to the build directory): anything else means the counts would
# be written and never read.
set(main_counts "${PROFILE}/sc_main#CMakeFiles#rbcd-sim.dir#main.cpp.gcda")
if(NOT EXISTS "${main_counts}")
  message(FATAL_ERROR "profile-guided build: the training wrote no ${main_counts} "
                      "(configure with -DRBCD_PGO=OFF to build without the profile)")
endif()
file(REMOVE_RECURSE ${WORK})
file(TOUCH ${STAMP})
