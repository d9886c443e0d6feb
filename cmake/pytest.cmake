# rbcd_add_pytest(FILE test_x.py PREFIX name [RELEASE_ONLY] [ENV VAR=value ...]
#                 [PROPERTIES prop value ...])
#
# The Python tests of one file, each in a CTest entry and a process of its
# own, as catch_discover_tests does for the C++ cases: the file's tests are
# collected when CMake configures (the file is a configure dependency, so a
# new test appears at the next build) and test_NAME becomes PREFIX_NAME.
# pytest runs from testbench/ (testbench/pytest.ini: the package from python/)
# with the built programs in RBCD_BIN (and ENV). A skipped test is reported
# skipped with its reason; a file whose every test is skipped at import (a
# module-level pytest.importorskip) is one entry, PREFIX_all, reported
# skipped; a file that does not import is one entry, PREFIX_collect, that
# fails showing why. Without python3-pytest (scripts/setup.sh installs it) each
# file gets one failing entry saying so: the suite never passes by running
# nothing.
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
  cmake_parse_arguments(P "RELEASE_ONLY" "FILE;PREFIX" "ENV;PROPERTIES" ${ARGN})
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
  # A parametrized test's id holds brackets, which a CMake list would take as
  # quoting (and merge the ids after it): they travel as placeholders.
  string(REPLACE "[" "<rbcd-lb>" out "${out}")
  string(REPLACE "]" "<rbcd-rb>" out "${out}")
  string(REPLACE ";" "<rbcd-sc>" out "${out}")
  string(REGEX MATCHALL "[^\n]+::[^\n]+" ids "${out}")
  if(rc EQUAL 5)        # nothing collected: the module skipped itself
    set(ids "${file}")
    set(whole all)
  elseif(NOT rc EQUAL 0 OR NOT ids)
    set(ids "${file}")
    set(whole collect)
    message(WARNING "pytest cannot collect the tests of ${P_FILE}: ${P_PREFIX}_collect shows why")
  endif()
  foreach(id ${ids})
    string(REGEX REPLACE ".*::test_" "" name "${id}")
    if(whole)
      set(name ${whole})
    endif()
    string(REPLACE "<rbcd-lb>" "[" id "${id}")
    string(REPLACE "<rbcd-rb>" "]" id "${id}")
    string(REPLACE "<rbcd-sc>" "\\;" id "${id}")
    string(REGEX REPLACE "<rbcd-..>" "_" name "${name}")
    string(REGEX REPLACE "[^A-Za-z0-9_.-]+" "_" name "${name}")
    string(REGEX REPLACE "_$" "" name "${name}")
    add_test(NAME ${P_PREFIX}_${name} COMMAND ${RBCD_PYTHON} -m pytest -q "${id}" WORKING_DIRECTORY ${tests})
    set_tests_properties(${P_PREFIX}_${name} PROPERTIES ENVIRONMENT "${env}" TIMEOUT 300
      SKIP_REGULAR_EXPRESSION "[0-9]+ skipped in " ${P_PROPERTIES})
    if(P_RELEASE_ONLY)
      set_tests_properties(${P_PREFIX}_${name} PROPERTIES LABELS release_only)
    endif()
  endforeach()
endfunction()
