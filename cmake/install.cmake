# `cmake --install`: the libraries, the public headers (tsm/*.h*, with the
# generated tsm/version.h), the CMake package (find_package(tsm) ->
# tsm::tsm, tsm::tsm_io, tsm::tsm_decoder) and tsm.pc for pkg-config.
include(CMakePackageConfigHelpers)

set(TSM_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/tsm CACHE STRING "Where the tsm CMake package goes")
set(TSM_INSTALL_PKGCONFIGDIR ${CMAKE_INSTALL_LIBDIR}/pkgconfig CACHE STRING "Where tsm.pc goes")

install(TARGETS tsm_decoder tsm tsm_io EXPORT tsmTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/libcodec/include/tsm ${PROJECT_SOURCE_DIR}/libio/include/tsm
                  ${PROJECT_BINARY_DIR}/include/tsm
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.h" PATTERN "*.hpp")
if(TSM_BUILD_TOOLS)
  install(TARGETS tsm_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

install(EXPORT tsmTargets NAMESPACE tsm:: FILE tsmTargets.cmake DESTINATION ${TSM_INSTALL_CMAKEDIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/tsmConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/tsmConfig.cmake
                              INSTALL_DESTINATION ${TSM_INSTALL_CMAKEDIR})
# 0.x: a minor release may break the API, so only the same major.minor matches.
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(TSM_COMPAT SameMinorVersion)
else()
  set(TSM_COMPAT SameMajorVersion)
endif()
write_basic_package_version_file(${PROJECT_BINARY_DIR}/tsmConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY ${TSM_COMPAT})
install(FILES ${PROJECT_BINARY_DIR}/tsmConfig.cmake ${PROJECT_BINARY_DIR}/tsmConfigVersion.cmake
        DESTINATION ${TSM_INSTALL_CMAKEDIR})

# tsm.pc: relocatable (prefix from where the file is), so
# `cmake --install <build> --prefix <anywhere>` gives a working file.
file(RELATIVE_PATH TSM_PC_TO_PREFIX ${CMAKE_INSTALL_PREFIX}/${TSM_INSTALL_PKGCONFIGDIR} ${CMAKE_INSTALL_PREFIX})
string(REGEX REPLACE "/$" "" TSM_PC_TO_PREFIX "${TSM_PC_TO_PREFIX}")
set(TSM_IO_PC_LIBS "")
if(TSM_IO_NEEDS_DRACO)
  string(APPEND TSM_IO_PC_LIBS " -ldraco")
endif()
if(TSM_IO_NEEDS_MESHOPT)
  string(APPEND TSM_IO_PC_LIBS " -lmeshoptimizer")
endif()
string(STRIP "${TSM_IO_PC_LIBS}" TSM_IO_PC_LIBS)
configure_file(${PROJECT_SOURCE_DIR}/cmake/tsm.pc.in ${PROJECT_BINARY_DIR}/tsm.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/tsm.pc DESTINATION ${TSM_INSTALL_PKGCONFIGDIR})
