# ctest package_downstream: installs this build into a fresh prefix, then configures, builds and
# runs examples/downstream against it with find_package(multicue CONFIG), and builds the same
# program a second time with the flags of pkg-config's multicue.pc. Only the example is compiled.
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DGENERATOR=... -DCXX_COMPILER=...
#         -DEXPECTED_VERSION=... [-DLIBDIR=lib]
#         [-DLAUNCHER=ccache] [-DPKG_CONFIG=pkg-config]
#         [-DPYTHON=python3 -DPYTHON_MODULE_DIR=lib/python3/dist-packages] -P package_downstream.cmake
cmake_minimum_required(VERSION 3.22)

if(NOT LIBDIR)
  set(LIBDIR lib)
endif()
foreach(_var BUILD_DIR SOURCE_DIR WORK_DIR GENERATOR CXX_COMPILER EXPECTED_VERSION)
  if(NOT DEFINED ${_var})
    message(FATAL_ERROR "package_downstream.cmake: -D${_var}=... is missing")
  endif()
endforeach()

function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})

run_step("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(f ${LIBDIR}/cmake/multicue/multicueConfig.cmake
          ${LIBDIR}/cmake/multicue/multicueConfigVersion.cmake
          ${LIBDIR}/cmake/multicue/multicueTargets.cmake ${LIBDIR}/pkgconfig/multicue.pc bin/multicue
          include/multicue/version.hpp include/multicue/core/point_cloud.hpp
          share/multicue/report/report.css)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "not installed: ${prefix}/${f}")
  endif()
endforeach()
file(GLOB_RECURSE private_headers ${prefix}/include/*_internal.hpp)
if(private_headers)
  message(FATAL_ERROR "private headers installed: ${private_headers}")
endif()

# The installed CLI runs from the prefix and knows its version.
run_step("multicue --version" ${prefix}/bin/multicue --version)
string(STRIP "${step_output}" version_line)
if(NOT version_line STREQUAL "multicue ${EXPECTED_VERSION}")
  message(FATAL_ERROR "multicue --version printed '${version_line}', "
                      "expected 'multicue ${EXPECTED_VERSION}'")
endif()
run_step("multicue demo" ${prefix}/bin/multicue demo --no-report --out ${WORK_DIR}/demo)
set(scene ${WORK_DIR}/demo/scene.pcd)

function(check_summary what text)
  foreach(expected "multicue ${EXPECTED_VERSION}" "points: 307200" "support plane: -?[0-9]")
    if(NOT text MATCHES "${expected}")
      message(FATAL_ERROR "${what}: output lacks '${expected}':\n${text}")
    endif()
  endforeach()
endfunction()

# find_package(multicue CONFIG REQUIRED) with CMAKE_PREFIX_PATH=prefix.
set(launcher_arg "")
if(LAUNCHER)
  set(launcher_arg -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
run_step("configure examples/downstream"
         ${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples/downstream -B ${WORK_DIR}/build
         -G ${GENERATOR} -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CXX_COMPILER}
         -DCMAKE_PREFIX_PATH=${prefix} ${launcher_arg})
run_step("build examples/downstream" ${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run_step("cloud_summary" ${WORK_DIR}/build/cloud_summary ${scene})
check_summary("cloud_summary (find_package)" "${step_output}")
set(cmake_summary "${step_output}")

# The same program from multicue.pc (static libraries need --static).
if(PKG_CONFIG)
  set(ENV{PKG_CONFIG_PATH} ${prefix}/${LIBDIR}/pkgconfig)
  run_step("pkg-config" ${PKG_CONFIG} --static --cflags --libs multicue)
  string(STRIP "${step_output}" pc_flags)
  separate_arguments(pc_flags UNIX_COMMAND "${pc_flags}")
  run_step("compile with pkg-config flags" ${LAUNCHER} ${CXX_COMPILER} -O2
           ${SOURCE_DIR}/examples/downstream/cloud_summary.cpp ${pc_flags}
           -o ${WORK_DIR}/cloud_summary_pc)
  # Shared libraries in a prefix the loader does not know (find_package builds get an RPATH).
  set(ENV{LD_LIBRARY_PATH} ${prefix}/${LIBDIR})
  run_step("cloud_summary (pkg-config)" ${WORK_DIR}/cloud_summary_pc ${scene})
  if(NOT step_output STREQUAL cmake_summary)
    message(FATAL_ERROR "pkg-config build printed\n${step_output}\nfind_package build printed\n"
                        "${cmake_summary}")
  endif()
endif()
# The installed Python module imports from the prefix and reads the scene.
if(PYTHON_MODULE_DIR)
  set(ENV{PYTHONPATH} ${prefix}/${PYTHON_MODULE_DIR})
  file(WRITE ${WORK_DIR}/import_multicue.py
       "import sys\nimport multicue\n"
       "print(multicue.__version__, len(multicue.read(sys.argv[1])), multicue.__file__)\n")
  run_step("installed Python module" ${PYTHON} ${WORK_DIR}/import_multicue.py ${scene})
  if(NOT step_output MATCHES "^${EXPECTED_VERSION} 307200 ${prefix}/")
    message(FATAL_ERROR "the installed Python module printed '${step_output}'")
  endif()
endif()
message(STATUS "package_downstream: ok\n${cmake_summary}")
