# PCL's io and common libraries only, found directly: PCLConfig.cmake drags in VTK, whose Debian
# config fails without MPI, and the interoperability tests need nothing but pcl_io.
# Defines the INTERFACE target multicue_pcl_io when PCL 1.13 is installed.
if(NOT TARGET multicue_pcl_io)
  find_path(MULTICUE_PCL_INCLUDE_DIR pcl/point_types.h PATH_SUFFIXES pcl-1.13)
  find_library(MULTICUE_PCL_COMMON_LIBRARY pcl_common)
  find_library(MULTICUE_PCL_IO_LIBRARY pcl_io)
  find_library(MULTICUE_PCL_IO_PLY_LIBRARY pcl_io_ply)
  find_package(Boost QUIET)
  if(MULTICUE_PCL_INCLUDE_DIR AND MULTICUE_PCL_COMMON_LIBRARY AND MULTICUE_PCL_IO_LIBRARY
     AND MULTICUE_PCL_IO_PLY_LIBRARY AND Boost_FOUND)
    add_library(multicue_pcl_io INTERFACE)
    target_include_directories(multicue_pcl_io SYSTEM INTERFACE ${MULTICUE_PCL_INCLUDE_DIR}
                               ${Boost_INCLUDE_DIRS})
    target_link_libraries(multicue_pcl_io INTERFACE ${MULTICUE_PCL_IO_LIBRARY}
                          ${MULTICUE_PCL_IO_PLY_LIBRARY} ${MULTICUE_PCL_COMMON_LIBRARY}
                          Eigen3::Eigen)
  endif()
endif()

# PCL's feature estimators and what they search with, for the feature oracle tests. Defines the
# INTERFACE target multicue_pcl_features (on top of multicue_pcl_io) when all are installed.
if(TARGET multicue_pcl_io AND NOT TARGET multicue_pcl_features)
  find_library(MULTICUE_PCL_FEATURES_LIBRARY pcl_features)
  find_library(MULTICUE_PCL_FILTERS_LIBRARY pcl_filters)
  find_library(MULTICUE_PCL_SEARCH_LIBRARY pcl_search)
  find_library(MULTICUE_PCL_KDTREE_LIBRARY pcl_kdtree)
  find_library(MULTICUE_PCL_OCTREE_LIBRARY pcl_octree)
  find_path(MULTICUE_FLANN_INCLUDE_DIR flann/flann.hpp)
  if(MULTICUE_PCL_FEATURES_LIBRARY AND MULTICUE_PCL_FILTERS_LIBRARY AND MULTICUE_PCL_SEARCH_LIBRARY
     AND MULTICUE_PCL_KDTREE_LIBRARY AND MULTICUE_PCL_OCTREE_LIBRARY AND MULTICUE_FLANN_INCLUDE_DIR)
    add_library(multicue_pcl_features INTERFACE)
    target_include_directories(multicue_pcl_features SYSTEM INTERFACE
                               ${MULTICUE_FLANN_INCLUDE_DIR})
    target_link_libraries(multicue_pcl_features INTERFACE ${MULTICUE_PCL_FEATURES_LIBRARY}
                          ${MULTICUE_PCL_FILTERS_LIBRARY} ${MULTICUE_PCL_SEARCH_LIBRARY}
                          ${MULTICUE_PCL_KDTREE_LIBRARY} ${MULTICUE_PCL_OCTREE_LIBRARY}
                          multicue_pcl_io)
  endif()
endif()
