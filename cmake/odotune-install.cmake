# `cmake --install build [--prefix P]` installs odotune as a CMake package:
#   P/bin/odotune
#   P/lib/libodotune_<module>.a              every module in ODOTUNE_MODULES
#   P/include/odotune/<module>/*.h           consumers include <odotune/tracks/track.h>
#   P/lib/cmake/odotune/odotune{Config,ConfigVersion,Targets*}.cmake
#   P/share/doc/odotune/                     README, CHANGELOG, LICENSE
# A consumer calls find_package(odotune REQUIRED) and links odotune::<module>
# (odotune::filters, odotune::tuner, …; odotune::odotune is the command).
# Everything here loops over ODOTUNE_MODULES, so a module declared with
# odotune_module() is installed and exported without an edit in this file.
# Included from CMakeLists.txt after the modules and the odotune executable.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(_odotune_export "")
foreach(m ${ODOTUNE_MODULES})
  set_target_properties(odotune_${m} PROPERTIES EXPORT_NAME ${m})
  list(APPEND _odotune_export odotune_${m})
  file(GLOB _hdrs CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/odotune/${m}/*.h)
  install(FILES ${_hdrs} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/odotune/${m})
endforeach()
# bags/ links the ROS 1 helper target publicly when it was found: its include
# directories and libraries are absolute system paths, so it exports as is.
if(TARGET odotune_ros1)
  set_target_properties(odotune_ros1 PROPERTIES EXPORT_NAME ros1)
  list(APPEND _odotune_export odotune_ros1)
endif()
set_target_properties(odotune PROPERTIES EXPORT_NAME odotune)

install(TARGETS odotune ${_odotune_export} EXPORT odotuneTargets
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
set(ODOTUNE_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/odotune)
install(EXPORT odotuneTargets NAMESPACE odotune:: DESTINATION ${ODOTUNE_INSTALL_CMAKEDIR})

# The config finds what the exported link interface names (see the LIBS of
# each odotune_module() and the find_package calls in CMakeLists.txt).
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/odotuneConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/odotuneConfig.cmake
                              INSTALL_DESTINATION ${ODOTUNE_INSTALL_CMAKEDIR})
# Before 1.0.0 a minor version may change the API (CHANGELOG.md).
write_basic_package_version_file(${PROJECT_BINARY_DIR}/odotuneConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/odotuneConfig.cmake ${PROJECT_BINARY_DIR}/odotuneConfigVersion.cmake
        DESTINATION ${ODOTUNE_INSTALL_CMAKEDIR})
install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/CHANGELOG.md ${PROJECT_SOURCE_DIR}/LICENSE
        DESTINATION ${CMAKE_INSTALL_DOCDIR})
