# rbcd_add_pytest(FILE test_x.py PREFIX name [RELEASE_ONLY] [ONE_PROCESS]
#                 [ENV VAR=value ...] [PROPERTIES prop value ...])
#
# The Python tests of one file as CTest entries: one entry and process per
# test function, all its parametrizations in that process; with ONE_PROCESS
# (files of unit tests that run in seconds) the whole file in one entry,
# PREFIX_all. A pytest process costs about 0.6 s before its first test
# (pytest, its plugins, the test module): as one process per parametrized
# case they had been 941 processes and about 9 minutes of CI's CPU. The
# file's tests are collected when CMake configures (the file is a configure
# dependency, so a new test appears at the next build) and test_NAME becomes
# PREFIX_NAME, which `ctest -R` selects; `pytest FILE::test_NAME[id]` runs one
# case. pytest runs from testbench/ (testbench/pytest.ini: the package from
# python/) with the built programs in RBCD_BIN (and ENV). An entry is
# reported skipped only when every test in it skipped (pytest's summary line
# is then "N skipped in"), with the reasons; a file whose every test is
# skipped at import (a module-level pytest.importorskip) is one entry,
# PREFIX_all, reported skipped; a file that does not import is one entry,
# PREFIX_collect, that fails showing why. Without python3-pytest
# (scripts/setup.sh installs it) each file gets one failing entry saying so:
# the suite never passes by running nothing.
#
# RELEASE_ONLY labels the file's tests release_only: scripts/test.sh
# --sanitize leaves them out. They test Python code, which the sanitizers do
# not see, and reach the project's C++ only as other tests do that run
# under the sanitizers (rbcd-gl-raster reading a well-formed draw stream:
# test_gl2rbt.py, the games_ tests and the draw_stream fuzz target); the
# preloaded libraries Mesa's replays use are never sanitized. Run twice they
# were about half of CI's time.
set(RBCD_PYTHON /usr/bin/python3)
execute_process(COMMAND ${RBCD_PYTHON} -c "import pytest" RESULT_VARIABLE RBCD_NO_PYTEST OUTPUT_QUIET ERROR_QUIET)

function(rbcd_add_pytest)
  cmake_parse_arguments(P "RELEASE_ONLY;ONE_PROCESS" "FILE;PREFIX" "ENV;PROPERTIES" ${ARGN})
  set(whole "")
  get_filename_component(file ${P_FILE} ABSOLUTE)
  set(tests ${PROJECT_SOURCE_DIR}/testbench)
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${file})
  # Compiled modules go to the build tree (PYTHONPYCACHEPREFIX), not beside
  # the sources, whatever the environment says of writing them
  # (PYTHONDONTWRITEBYTECODE empty is unset): every test is a process of its
  # own, and the package and the test modules compiled again in each had been
  # a third of a unit test's time.
  set(env "RBCD_BIN=${PROJECT_BINARY_DIR}/bin;PYTHONPYCACHEPREFIX=${PROJECT_BINARY_DIR}/pycache;PYTHONDONTWRITEBYTECODE=;${RBCD_TEST_ENV};${P_ENV}")
  if(RBCD_NO_PYTEST)
    add_test(NAME ${P_PREFIX}_pytest_missing
      COMMAND sh -c "echo 'python3-pytest is missing: scripts/setup.sh installs it'; exit 1")
    message(WARNING "python3-pytest is missing: the tests of ${P_FILE} fail (scripts/setup.sh installs it)")
    return()
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} -E env PYTHONPYCACHEPREFIX=${PROJECT_BINARY_DIR}/pycache
      --unset=PYTHONDONTWRITEBYTECODE ${RBCD_PYTHON} -m pytest --collect-only -q ${file}
    WORKING_DIRECTORY ${tests} OUTPUT_VARIABLE out ERROR_VARIABLE err RESULT_VARIABLE rc)
  # A test's id is FILE::test_NAME, then [PARAMETERS] for a parametrized
  # one: the entries are the ids without their parameters, once each. The
  # parameters may hold brackets and semicolons, which a CMake list would
  # take as quoting and separators: they are cut off before the list is made.
  string(REGEX REPLACE "\\[[^\n]*" "" out "${out}")
  string(REPLACE ";" "_" out "${out}")
  string(REGEX MATCHALL "[^\n]+::[^\n]+" ids "${out}")
  list(REMOVE_DUPLICATES ids)
  if(rc EQUAL 5)        # nothing collected: the module skipped itself
    set(ids "${file}")
    set(whole all)
  elseif(NOT rc EQUAL 0 OR NOT ids)
    set(ids "${file}")
    set(whole collect)
    message(WARNING "pytest cannot collect the tests of ${P_FILE}: ${P_PREFIX}_collect shows why")
  elseif(P_ONE_PROCESS)
    set(ids "${file}")
    set(whole all)
  endif()
  foreach(id ${ids})
    string(REGEX REPLACE ".*::test_" "" name "${id}")
    if(whole)
      set(name ${P_PREFIX}_${whole})
    else()
      string(REGEX REPLACE "[^A-Za-z0-9_.-]+" "_" name "${P_PREFIX}_${name}")
    endif()
    add_test(NAME ${name} COMMAND ${RBCD_PYTHON} -m pytest -q "${id}" WORKING_DIRECTORY ${tests})
    # Skipped when pytest's last line is "N skipped in ...": every test of the
    # entry skipped ("3 passed, 2 skipped in" is a pass, "1 failed, ..." a failure).
    set_tests_properties(${name} PROPERTIES ENVIRONMENT "${env}" TIMEOUT 600
      SKIP_REGULAR_EXPRESSION "\n[0-9]+ skipped in " ${P_PROPERTIES})
    if(P_RELEASE_ONLY)
      set_tests_properties(${name} PROPERTIES LABELS release_only)
    endif()
  endforeach()
endfunction()
