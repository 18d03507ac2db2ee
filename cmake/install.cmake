# The installed package: `cmake --install BUILD --prefix PREFIX` puts the headers under
# PREFIX/include/idyvins/<module>/, the libraries under PREFIX/lib, and
# idyvinsConfig.cmake (targets idyvins::<module>, idyvins::idyvins for all of them) and
# idyvins.pc for pkg-config. A consumer: find_package(idyvins) + idyvins::idyvins.

include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(IDYVINS_LIBRARY_MODULES core camera imu io config frontend dynamic backend eval sim map pipeline)
if(IDYVINS_BUILD_BAG)
  list(APPEND IDYVINS_LIBRARY_MODULES bag)
endif()
set(IDYVINS_LIBRARY_TARGETS)
foreach(module ${IDYVINS_LIBRARY_MODULES})
  set_target_properties(idyvins_${module} PROPERTIES EXPORT_NAME ${module})
  list(APPEND IDYVINS_LIBRARY_TARGETS idyvins_${module})
endforeach()
# idyvins::idyvins: every library module, what an embedder of pipeline::System links.
add_library(idyvins_all INTERFACE)
set_target_properties(idyvins_all PROPERTIES EXPORT_NAME idyvins)
target_link_libraries(idyvins_all INTERFACE ${IDYVINS_LIBRARY_TARGETS})

install(TARGETS ${IDYVINS_LIBRARY_TARGETS} idyvins_all EXPORT idyvinsTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/src/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/idyvins
        FILES_MATCHING PATTERN "*.h")
if(IDYVINS_BUILD_CLI)
  install(TARGETS idyvins RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

set(IDYVINS_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/idyvins)
install(EXPORT idyvinsTargets NAMESPACE idyvins:: DESTINATION ${IDYVINS_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/idyvinsConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/idyvinsConfig.cmake INSTALL_DESTINATION ${IDYVINS_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/idyvinsConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/idyvinsConfig.cmake ${PROJECT_BINARY_DIR}/idyvinsConfigVersion.cmake
        DESTINATION ${IDYVINS_CMAKE_DIR})

# pkg-config: the libraries in link order (each before what it uses).
set(IDYVINS_PC_LIBS "")
set(IDYVINS_PC_MODULES pipeline sim eval map backend dynamic frontend config io imu camera core)
if(IDYVINS_BUILD_BAG)  # pipeline::openDataset reads bags: the bag module and Debian's rosbag_storage
  set(IDYVINS_PC_MODULES pipeline bag sim eval map backend dynamic frontend config io imu camera core)
endif()
foreach(module ${IDYVINS_PC_MODULES})
  string(APPEND IDYVINS_PC_LIBS " -lidyvins_${module}")
endforeach()
if(IDYVINS_BUILD_BAG)
  string(APPEND IDYVINS_PC_LIBS " -lrosbag_storage -lroscpp_serialization -lrostime -lcpp_common -lconsole_bridge -lroslz4 -lzstd -llz4 -lsqlite3 -lz")
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/idyvins.pc.in ${PROJECT_BINARY_DIR}/idyvins.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/idyvins.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
