# Installation and the CMake package (find_package(multicue CONFIG)) and pkg-config file.
#   cmake --install build --prefix PREFIX
# installs
#   PREFIX/lib/libmulticue_<module>.{a,so}           one library per module (BUILD_SHARED_LIBS)
#   PREFIX/include/multicue/<module>/*.hpp           public headers, multicue/version.hpp
#   PREFIX/bin/multicue                              the CLI
#   PREFIX/share/multicue/report/                    the report page's style and viewer script
#   PREFIX/lib/cmake/multicue/                       multicueConfig.cmake, version, targets
#   PREFIX/lib/pkgconfig/multicue.pc
# docs/using-the-library.md shows how a project uses them.
include(CMakePackageConfigHelpers)

set(MULTICUE_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/multicue CACHE STRING
    "Where multicueConfig.cmake is installed, relative to the prefix")

get_property(_multicue_modules GLOBAL PROPERTY MULTICUE_MODULES)
install(TARGETS ${_multicue_modules} multicue_lzf
        EXPORT multicueTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
if(TARGET multicue_adapters)
  install(TARGETS multicue_adapters EXPORT multicueTargets)
endif()
install(TARGETS multicue RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

# Public headers: every module header but the private ones of the readers and sample consensus.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/src/multicue/
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/multicue
        FILES_MATCHING PATTERN "*.hpp"
        PATTERN "*_internal.hpp" EXCLUDE)
install(FILES ${PROJECT_BINARY_DIR}/include/multicue/version.hpp
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/multicue)

# The report page's assets as compiled into the CLI, for pages made by other tools.
install(FILES ${PROJECT_SOURCE_DIR}/web/src/report.css
        DESTINATION ${CMAKE_INSTALL_DATADIR}/multicue/report)
get_property(_multicue_viewer_js GLOBAL PROPERTY MULTICUE_REPORT_VIEWER_JS)
if(_multicue_viewer_js)
  install(FILES ${_multicue_viewer_js} DESTINATION ${CMAKE_INSTALL_DATADIR}/multicue/report)
endif()

install(EXPORT multicueTargets
        NAMESPACE multicue::
        FILE multicueTargets.cmake
        DESTINATION ${MULTICUE_INSTALL_CMAKEDIR})
# The same targets for a build tree used without installing (-Dmulticue_DIR=build).
export(EXPORT multicueTargets NAMESPACE multicue::
       FILE ${PROJECT_BINARY_DIR}/multicueTargets.cmake)

set(MULTICUE_CONFIG_SHARED ${BUILD_SHARED_LIBS})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/multicueConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/multicueConfig.cmake
                              INSTALL_DESTINATION ${MULTICUE_INSTALL_CMAKEDIR})
# 0.x: only the same minor version is compatible (as the SOVERSION says).
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(_multicue_compat SameMinorVersion)
else()
  set(_multicue_compat SameMajorVersion)
endif()
write_basic_package_version_file(${PROJECT_BINARY_DIR}/multicueConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY ${_multicue_compat})
install(FILES ${PROJECT_BINARY_DIR}/multicueConfig.cmake
              ${PROJECT_BINARY_DIR}/multicueConfigVersion.cmake
        DESTINATION ${MULTICUE_INSTALL_CMAKEDIR})

# pkg-config: the module libraries, dependents first for static linkers.
set(_pc_libs "")
list(REVERSE _multicue_modules)
foreach(_m IN LISTS _multicue_modules)
  string(APPEND _pc_libs " -l${_m}")
endforeach()
if(BUILD_SHARED_LIBS)
  set(MULTICUE_PC_LIBS_PRIVATE "")
else()
  # What the static libraries need from their private dependencies.
  set(MULTICUE_PC_LIBS_PRIVATE
      "-llzf -lsqlite3 -lembree3 -lassimp -lopencv_ml -lopencv_features2d -lopencv_imgproc \
-lopencv_flann -lopencv_core -lpng16 -ljpeg -lsvm -lurdfdom_model -ltinyxml -lconsole_bridge \
-loctomap -loctomath")
  # MCAP chunk decompression in multicue::io (optional, see src/multicue/io/CMakeLists.txt).
  if(MULTICUE_ZSTD_LIBRARY)
    string(APPEND MULTICUE_PC_LIBS_PRIVATE " -lzstd")
  endif()
  if(MULTICUE_LZ4_LIBRARY)
    string(APPEND MULTICUE_PC_LIBS_PRIVATE " -llz4")
  endif()
endif()
set(MULTICUE_PC_LIBS "${_pc_libs}")
# Relocatable: the prefix is found from the .pc file's own folder (cmake --install --prefix P).
file(RELATIVE_PATH MULTICUE_PC_PREFIX_FROM_PCDIR ${CMAKE_INSTALL_FULL_LIBDIR}/pkgconfig
     ${CMAKE_INSTALL_PREFIX})
string(REGEX REPLACE "/$" "" MULTICUE_PC_PREFIX_FROM_PCDIR "${MULTICUE_PC_PREFIX_FROM_PCDIR}")
configure_file(${PROJECT_SOURCE_DIR}/cmake/multicue.pc.in ${PROJECT_BINARY_DIR}/multicue.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/multicue.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
