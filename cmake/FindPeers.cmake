# The peer libraries the benchmarks compare against: PCL 1.13 and Open3D 0.16.
# PCL's libraries are found directly (as in FindPclIo.cmake: PCLConfig.cmake drags in VTK, whose
# Debian config fails without MPI). Open3D's own CMake config works and is used.
# Defines the INTERFACE target multicue_bench_peers when all of them are found, and fails with a
# message naming what is missing otherwise.
if(NOT TARGET multicue_bench_peers)
  set(_peer_missing "")

  find_path(MULTICUE_PCL_INCLUDE_DIR pcl/point_types.h PATH_SUFFIXES pcl-1.13)
  if(NOT MULTICUE_PCL_INCLUDE_DIR)
    list(APPEND _peer_missing "PCL 1.13 headers (libpcl-dev)")
  endif()
  set(_peer_pcl_libraries "")
  # Dependents first, for static linkers; the shared libraries bring flann and lz4 themselves.
  # pcl_segmentation and pcl_sample_consensus are for mosd_peers.
  foreach(_lib IN ITEMS pcl_segmentation pcl_sample_consensus pcl_features pcl_filters pcl_search
                        pcl_kdtree pcl_octree pcl_io pcl_io_ply pcl_common)
    string(TOUPPER ${_lib} _var)
    find_library(MULTICUE_${_var}_LIBRARY ${_lib})
    if(MULTICUE_${_var}_LIBRARY)
      list(APPEND _peer_pcl_libraries ${MULTICUE_${_var}_LIBRARY})
    else()
      list(APPEND _peer_missing "lib${_lib} (libpcl-dev)")
    endif()
  endforeach()
  find_package(Boost QUIET)
  if(NOT Boost_FOUND)
    list(APPEND _peer_missing "Boost headers (PCL's io headers need them)")
  endif()
  find_path(MULTICUE_FLANN_INCLUDE_DIR flann/flann.hpp)
  if(NOT MULTICUE_FLANN_INCLUDE_DIR)
    list(APPEND _peer_missing "FLANN headers (libflann-dev)")
  endif()

  # No version in the call: Open3D's version file accepts only an exact match (0.16.1).
  find_package(Open3D CONFIG QUIET HINTS /usr/lib/x86_64-linux-gnu/cmake/Open3D)
  if(NOT Open3D_FOUND)
    list(APPEND _peer_missing "Open3D 0.16 (libopen3d-dev)")
  elseif(NOT Open3D_VERSION MATCHES "^0\\.16(\\.|$)")
    message(WARNING "Benchmark peers: found Open3D ${Open3D_VERSION}, the comparison is for 0.16")
  endif()

  # Both peers parallelize with OpenMP; the benchmarks set its thread count.
  find_package(OpenMP QUIET COMPONENTS CXX)
  if(NOT OpenMP_CXX_FOUND)
    list(APPEND _peer_missing "OpenMP for C++")
  endif()

  if(_peer_missing)
    string(REPLACE ";" ", " _peer_missing "${_peer_missing}")
    message(FATAL_ERROR "MULTICUE_BENCH_PEERS=ON but these are missing: ${_peer_missing}. "
                        "Install them or configure with -DMULTICUE_BENCH_PEERS=OFF.")
  endif()

  add_library(multicue_bench_peers INTERFACE)
  target_include_directories(multicue_bench_peers SYSTEM INTERFACE ${MULTICUE_PCL_INCLUDE_DIR}
                             ${MULTICUE_FLANN_INCLUDE_DIR} ${Boost_INCLUDE_DIRS})
  target_link_libraries(multicue_bench_peers INTERFACE ${_peer_pcl_libraries} Open3D::Open3D
                        OpenMP::OpenMP_CXX Eigen3::Eigen)
  message(STATUS "Benchmark peers: PCL at ${MULTICUE_PCL_INCLUDE_DIR}, Open3D ${Open3D_VERSION}")
endif()
