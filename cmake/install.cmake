# `cmake --install build --prefix P` (docs/embedding.md):
#   P/lib/librbcd_{common,io,tlm,hw}.a  the unit, TLM and trace input (rbcd::unit)
#   P/lib/librbcd_scene.a               the scene front end (rbcd::scene, COMPONENTS scene)
#   P/include/rbcd/{common,hw,io,scene,tlm}/*.h
#   P/lib/cmake/rbcd/                   find_package(rbcd CONFIG [COMPONENTS scene])
#   P/lib/pkgconfig/rbcd.pc             the unit for pkg-config builds
#   P/bin/rbcd-sim, P/bin/rbcd-merge, P/bin/rbcd-gl-raster
#   P/lib/rbcd/rbcd-es-depth-readback.so  preloaded into glretrace by --check-depth
#   P/lib/rbcd/rbcd-texture-readback.so   preloaded into glretrace for rendered textures
#   P/bin/rbcd-sweep, rbcd-plot, rbcd-gl2rbt  launchers of the Python package
#   P/share/rbcd/python/rbcd/               the package (docs/python.md)
#   P/share/rbcd/configs/*.toml, P/share/doc/rbcd/ (README, docs)
include(CMakePackageConfigHelpers)

# Two export sets, so that a platform that links only the unit needs only
# SystemC (and zlib's library) found, never Eigen, assimp or libpng.
install(TARGETS rbcd_common rbcd_io rbcd_tlm rbcd_hw rbcd_unit EXPORT rbcdUnitTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS rbcd_scene rbcd EXPORT rbcdSceneTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
# Consumers add P/include and write "rbcd/hw/zeb_bank.h", as the tree does.
foreach(area common hw io scene tlm)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${area}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/rbcd/${area}
    FILES_MATCHING PATTERN "*.h")
endforeach()

foreach(program rbcd-sim rbcd-merge rbcd-gl-raster)
  if(TARGET ${program})
    install(TARGETS ${program} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endforeach()
# Beside bin/ as lib/rbcd/ (not CMAKE_INSTALL_LIBDIR: rbcd-gl2rbt finds it
# from rbcd-gl-raster's folder, whatever the platform's library folder).
foreach(library rbcd-es-depth-readback rbcd-texture-readback)
  if(TARGET ${library})
    install(TARGETS ${library} LIBRARY DESTINATION lib/rbcd)
  endif()
endforeach()
# The Python tools: the package, and the launchers of scripts/ with the path
# from P/bin to the package in place of the source tree's. rbcd-gl2rbt finds
# rbcd-gl-raster beside itself (docs/gl-capture.md).
install(DIRECTORY ${PROJECT_SOURCE_DIR}/python/rbcd DESTINATION ${CMAKE_INSTALL_DATADIR}/rbcd/python
  FILES_MATCHING PATTERN "*.py" PATTERN __pycache__ EXCLUDE)
# rbcd-sweep counts the default input's frames for [split] from the scene.
install(FILES ${PROJECT_SOURCE_DIR}/scene/default_scene.toml DESTINATION ${CMAKE_INSTALL_DATADIR}/rbcd/scene)
file(RELATIVE_PATH rbcd_python_rel /p/${CMAKE_INSTALL_BINDIR} /p/${CMAKE_INSTALL_DATADIR}/rbcd/python)
set(rbcd_launchers rbcd-sweep rbcd-plot)
if(TARGET rbcd-gl-raster)
  list(APPEND rbcd_launchers rbcd-gl2rbt)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/workloads/games/ DESTINATION ${CMAKE_INSTALL_DATADIR}/rbcd/games
    FILES_MATCHING PATTERN "*.toml")
endif()
foreach(tool ${rbcd_launchers})
  file(READ ${PROJECT_SOURCE_DIR}/scripts/${tool} text)
  set(source_paths [=[("../python", "../share/rbcd/python")]=])
  string(FIND "${text}" "${source_paths}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "scripts/${tool} is not a launcher of the package: it names no ${source_paths}")
  endif()
  string(REPLACE "${source_paths}" "(\"${rbcd_python_rel}\",)" text "${text}")
  file(WRITE ${PROJECT_BINARY_DIR}/launchers/${tool} "${text}")
  install(PROGRAMS ${PROJECT_BINARY_DIR}/launchers/${tool} DESTINATION ${CMAKE_INSTALL_BINDIR})
endforeach()
install(DIRECTORY ${PROJECT_SOURCE_DIR}/sc_main/configs/ DESTINATION ${CMAKE_INSTALL_DATADIR}/rbcd/configs
  FILES_MATCHING PATTERN "*.toml")
install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rbcd)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rbcd)

set(RBCD_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/rbcd)
install(EXPORT rbcdUnitTargets NAMESPACE rbcd:: DESTINATION ${RBCD_CMAKE_DIR})
install(EXPORT rbcdSceneTargets NAMESPACE rbcd:: DESTINATION ${RBCD_CMAKE_DIR})
# How the package finds SystemC is decided here, the way this build found it.
if(RBCD_SYSTEMC_TARGET STREQUAL "PkgConfig::SYSTEMC")
  set(RBCD_FIND_SYSTEMC [=[find_dependency(PkgConfig)
pkg_check_modules(SYSTEMC QUIET IMPORTED_TARGET systemc)
if(NOT TARGET PkgConfig::SYSTEMC)
  set(rbcd_FOUND FALSE)
  set(rbcd_NOT_FOUND_MESSAGE "rbcd needs SystemC: pkg-config found no systemc.pc (Debian: libsystemc-dev)")
  return()
endif()]=])
else()
  set(RBCD_FIND_SYSTEMC "find_dependency(SystemCLanguage CONFIG)")
endif()
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/rbcdConfig.cmake.in
  ${PROJECT_BINARY_DIR}/rbcdConfig.cmake INSTALL_DESTINATION ${RBCD_CMAKE_DIR})
# 0.x: a minor version may change the interface.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/rbcdConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/rbcdConfig.cmake ${PROJECT_BINARY_DIR}/rbcdConfigVersion.cmake
  DESTINATION ${RBCD_CMAKE_DIR})

# pkg-config: the unit (rbcd::unit's archives), relocatable (paths from the .pc's own place).
file(RELATIVE_PATH RBCD_PC_PREFIX /p/${CMAKE_INSTALL_LIBDIR}/pkgconfig /p)
string(REGEX REPLACE "/$" "" RBCD_PC_PREFIX "${RBCD_PC_PREFIX}")
if(RBCD_SYSTEMC_TARGET STREQUAL "PkgConfig::SYSTEMC")
  set(RBCD_PC_REQUIRES "systemc zlib libzstd")
else()
  set(RBCD_PC_REQUIRES "zlib libzstd")   # SystemC from its CMake package: give its flags yourself
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/rbcd.pc.in ${PROJECT_BINARY_DIR}/rbcd.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/rbcd.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
