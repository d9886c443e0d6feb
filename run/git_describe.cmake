# Run at every build (target rbcd_git_describe): writes OUT with the source
# tree's `git describe --always --dirty`, or "" when SRC is not a git checkout
# or git is missing; FIXED instead when given (the profile-guided build's
# instrumented copy). configure_file leaves OUT untouched when the text is the
# same, so provenance.cpp recompiles only when the revision changes.
set(RBCD_GIT_DESCRIBE "")
if(DEFINED FIXED)
  set(RBCD_GIT_DESCRIBE "${FIXED}")
elseif(GIT)
  # Only when SRC is the top of a checkout: a source tarball unpacked inside
  # some other git repository must not take that repository's revision.
  execute_process(COMMAND ${GIT} -C ${SRC} rev-parse --show-toplevel
                  OUTPUT_VARIABLE _top RESULT_VARIABLE _rc ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
  get_filename_component(_src_real "${SRC}" REALPATH)
  get_filename_component(_top_real "${_top}" REALPATH)
  if(_rc EQUAL 0 AND _top_real STREQUAL _src_real)
    execute_process(COMMAND ${GIT} -C ${SRC} describe --always --dirty
                    OUTPUT_VARIABLE _out RESULT_VARIABLE _rc ERROR_QUIET OUTPUT_STRIP_TRAILING_WHITESPACE)
    if(_rc EQUAL 0)
      set(RBCD_GIT_DESCRIBE "${_out}")
    endif()
  endif()
endif()
file(WRITE ${OUT}.new "// Generated at build time by run/git_describe.cmake.\n#pragma once\n#define RBCD_GIT_DESCRIBE \"${RBCD_GIT_DESCRIBE}\"\n")
configure_file(${OUT}.new ${OUT} COPYONLY)
file(REMOVE ${OUT}.new)
