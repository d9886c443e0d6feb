# `cmake --install build --prefix P` (docs/embedding.md):
#   P/lib/librbcd.a                      the model (rbcd::rbcd)
#   P/include/rbcd/{common,hw,io,scene,tlm}/*.h
#   P/lib/cmake/rbcd/                    find_package(rbcd CONFIG)
#   P/bin/rbcd-sim, P/bin/rbcd-merge, P/bin/rbcd-gl2rbt and rbcd-gl-raster
#   P/share/rbcd/configs/*.toml, P/share/doc/rbcd/ (README, docs)
include(CMakePackageConfigHelpers)

install(TARGETS rbcd EXPORT rbcdTargets
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
# rbcd-gl2rbt finds rbcd-gl-raster beside itself (docs/gl-capture.md).
if(TARGET rbcd-gl-raster)
  install(PROGRAMS ${PROJECT_SOURCE_DIR}/scripts/rbcd-gl2rbt DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(FILES ${PROJECT_SOURCE_DIR}/scripts/rbcd_cli.py DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/workloads/games/ DESTINATION ${CMAKE_INSTALL_DATADIR}/rbcd/games
    FILES_MATCHING PATTERN "*.toml")
endif()
install(DIRECTORY ${PROJECT_SOURCE_DIR}/sc_main/configs/ DESTINATION ${CMAKE_INSTALL_DATADIR}/rbcd/configs
  FILES_MATCHING PATTERN "*.toml")
install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rbcd)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rbcd)

set(RBCD_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/rbcd)
install(EXPORT rbcdTargets NAMESPACE rbcd:: DESTINATION ${RBCD_CMAKE_DIR})
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
