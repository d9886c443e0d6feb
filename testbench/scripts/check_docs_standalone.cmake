# The README and docs/ stand alone: no reference outside the repository (the
# interface specification lives elsewhere; docs/formats.md and docs/contract.md
# carry it), and every docs/NAME.md they name exists.
#   cmake -DSRC=<source dir> -P check_docs_standalone.cmake
file(GLOB docs ${SRC}/docs/*.md)
set(bad "")
foreach(f ${SRC}/README.md ${docs})
  file(READ ${f} text)
  foreach(outside "../shared" "/work/shared" "shared/spec")
    string(FIND "${text}" "${outside}" at)
    if(NOT at EQUAL -1)
      string(APPEND bad "\n  ${f}: refers to '${outside}'")
    endif()
  endforeach()
  string(REGEX MATCHALL "docs/[A-Za-z0-9_.-]+\\.md" named "${text}")
  foreach(n ${named})
    if(NOT EXISTS ${SRC}/${n})
      string(APPEND bad "\n  ${f}: names ${n}, which does not exist")
    endif()
  endforeach()
endforeach()
if(bad)
  message(FATAL_ERROR "docs do not stand alone:${bad}")
endif()
