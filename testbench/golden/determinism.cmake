# Determinism: runs rbcd-sim twice on one input with --collisions, --stats and
# --vcd, and requires the outputs to be byte-identical between the runs and to
# the committed goldens (testbench/golden/determinism/NAME.*), wall time aside:
# stats' wall_seconds and fragments_per_second are zeroed and its provenance
# block (build, command line, output paths) removed, the VCD's $date and
# $version removed. Every build type (Release, sanitizer, clang) compares with
# the same goldens.
#   -DSIM=... -DSRC=<source dir> -DNAME=... -DGOLDEN_DIR=... -DOUT_DIR=... -DARGS=a,b [-DREGENERATE=ON]
# Regenerate all goldens deliberately (after a change that alters results):
#   cmake --build build --target regenerate-determinism-goldens
string(REPLACE "," ";" ARGS "${ARGS}")   # given comma-separated
file(MAKE_DIRECTORY ${OUT_DIR})
function(normalize kind in out)
  file(READ ${in} text)
  if(kind STREQUAL "stats.json")
    string(REGEX REPLACE "\"wall_seconds\": [^,\n]*" "\"wall_seconds\": 0" text "${text}")
    string(REGEX REPLACE "\"fragments_per_second\": [^,\n]*" "\"fragments_per_second\": 0" text "${text}")
    string(JSON text REMOVE "${text}" provenance)
  elseif(kind STREQUAL "vcd")
    string(REGEX REPLACE "\\$date[^$]*\\$end\n" "" text "${text}")
    string(REGEX REPLACE "\\$version[^$]*\\$end\n" "" text "${text}")
  endif()
  set(${out} "${text}" PARENT_SCOPE)
endfunction()
set(kinds collisions stats.json vcd)
foreach(run 1 2)
  set(p ${OUT_DIR}/${NAME}.run${run})
  # Relative input paths: stats.json names the input as given.
  execute_process(COMMAND ${SIM} ${ARGS} -q --collisions ${p}.collisions --stats ${p}.stats.json --vcd ${p}.vcd
                  WORKING_DIRECTORY ${SRC} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "rbcd-sim ${ARGS} exited ${rc}")
  endif()
  foreach(k ${kinds})
    normalize(${k} ${p}.${k} text)
    set(run${run}_${k} "${text}")
  endforeach()
endforeach()
foreach(k ${kinds})
  if(NOT run1_${k} STREQUAL run2_${k})
    message(FATAL_ERROR "${NAME}: ${k} differs between two identical runs: compare ${OUT_DIR}/${NAME}.run1.${k} and .run2.${k}")
  endif()
  set(golden ${GOLDEN_DIR}/${NAME}.${k})
  if(REGENERATE)
    file(WRITE ${golden} "${run1_${k}}")
    message(STATUS "wrote ${golden}")
  else()
    file(READ ${golden} want)
    if(NOT run1_${k} STREQUAL want)
      file(WRITE ${OUT_DIR}/${NAME}.normalized.${k} "${run1_${k}}")
      message(FATAL_ERROR "${NAME}: ${k} differs from ${golden}: compare ${OUT_DIR}/${NAME}.normalized.${k}; "
                          "if the change is intended: cmake --build build --target regenerate-determinism-goldens")
    endif()
  endif()
endforeach()
