# Runs rbcd-sim with --vcd and compares the dump with a golden file, both with
# the $date and $version sections removed (they change with every build/run).
#   -DSIM=... -DTRACE=... -DGOLDEN=... -DOUT=... [-DARGS="a;b"]
execute_process(COMMAND ${SIM} --trace ${TRACE} --vcd ${OUT} -q ${ARGS} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rbcd-sim exited ${rc}")
endif()
function(strip_vcd in out)
  file(READ ${in} text)
  string(REGEX REPLACE "\\$date[^$]*\\$end\n" "" text "${text}")
  string(REGEX REPLACE "\\$version[^$]*\\$end\n" "" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()
strip_vcd(${OUT} got)
strip_vcd(${GOLDEN} want)
if(NOT got STREQUAL want)
  file(WRITE ${OUT}.stripped "${got}")
  message(FATAL_ERROR "VCD differs from ${GOLDEN}: compare ${OUT}.stripped (regenerate deliberately with --vcd and strip $date/$version)")
endif()
