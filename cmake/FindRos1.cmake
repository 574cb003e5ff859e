# ROS 1 as Debian 12 packages it (libroscpp-dev, librosbag-dev, message headers): libraries and
# headers found directly, since the catkin package configs need a catkin environment.
# MULTICUE_ROS (AUTO, ON, OFF) decides; defines
#   multicue_ros1_bag_deps  INTERFACE target: librosbag_storage and what its headers need
#   multicue_roscpp_deps    INTERFACE target: roscpp and the message headers of the node
#   MULTICUE_ROS1_BAG_FOUND, MULTICUE_ROSCPP_FOUND, MULTICUE_GENCPP (gen_cpp.py) and
#   MULTICUE_ROS_PYTHON (an interpreter that imports genmsg)
set(MULTICUE_ROS AUTO CACHE STRING "ROS 1 bag reading and the ROS node: AUTO, ON or OFF")
set_property(CACHE MULTICUE_ROS PROPERTY STRINGS AUTO ON OFF)
set(MULTICUE_ROS1_BAG_FOUND OFF)
set(MULTICUE_ROSCPP_FOUND OFF)
if(NOT MULTICUE_ROS STREQUAL "OFF" AND NOT TARGET multicue_ros1_bag_deps)
  find_path(MULTICUE_ROSBAG_INCLUDE_DIR rosbag/bag.h)
  # rosbag/bag.h includes pluginlib, which Debian ships in its ROS 2 layout: each package's
  # headers in their own folder under /usr/include.
  set(_ros_bag_include_dirs "")
  set(_ros_bag_headers_ok ON)
  foreach(_h IN ITEMS pluginlib/class_loader.hpp class_loader/multi_library_class_loader.hpp
                      rcpputils/shared_library.hpp rcutils/shared_library.h
                      ament_index_cpp/get_package_prefix.hpp)
    string(REGEX REPLACE "/.*" "" _pkg ${_h})
    find_path(MULTICUE_ROS_${_pkg}_INCLUDE_DIR ${_h} PATH_SUFFIXES ${_pkg})
    if(MULTICUE_ROS_${_pkg}_INCLUDE_DIR)
      list(APPEND _ros_bag_include_dirs ${MULTICUE_ROS_${_pkg}_INCLUDE_DIR})
    else()
      set(_ros_bag_headers_ok OFF)
    endif()
  endforeach()
  find_package(Boost QUIET COMPONENTS filesystem system)
  set(_ros_libs rosbag_storage roslz4 roscpp_serialization rostime cpp_common console_bridge)
  set(_ros_bag_ok ON)
  set(_ros_bag_libs "")
  foreach(_l IN LISTS _ros_libs)
    find_library(MULTICUE_ROS_${_l}_LIBRARY ${_l})
    if(MULTICUE_ROS_${_l}_LIBRARY)
      list(APPEND _ros_bag_libs ${MULTICUE_ROS_${_l}_LIBRARY})
    else()
      set(_ros_bag_ok OFF)
    endif()
  endforeach()
  if(_ros_bag_ok AND _ros_bag_headers_ok AND MULTICUE_ROSBAG_INCLUDE_DIR AND Boost_FOUND)
    add_library(multicue_ros1_bag_deps INTERFACE)
    target_include_directories(multicue_ros1_bag_deps SYSTEM INTERFACE
                               ${MULTICUE_ROSBAG_INCLUDE_DIR} ${_ros_bag_include_dirs}
                               ${Boost_INCLUDE_DIRS})
    target_link_libraries(multicue_ros1_bag_deps INTERFACE ${_ros_bag_libs} Boost::filesystem
                          Boost::system)
    set(MULTICUE_ROS1_BAG_FOUND ON)
  endif()

  find_path(MULTICUE_ROSCPP_INCLUDE_DIR ros/ros.h)
  find_path(MULTICUE_SENSOR_MSGS_INCLUDE_DIR sensor_msgs/PointCloud2.h)
  find_path(MULTICUE_VIS_MSGS_INCLUDE_DIR visualization_msgs/MarkerArray.h)
  find_path(MULTICUE_STD_MSGS_INCLUDE_DIR std_msgs/String.h)
  set(_roscpp_libs roscpp rosconsole roscpp_serialization rostime xmlrpcpp cpp_common)
  set(_roscpp_ok ON)
  set(_roscpp_found_libs "")
  foreach(_l IN LISTS _roscpp_libs)
    find_library(MULTICUE_ROS_${_l}_LIBRARY ${_l})
    if(MULTICUE_ROS_${_l}_LIBRARY)
      list(APPEND _roscpp_found_libs ${MULTICUE_ROS_${_l}_LIBRARY})
    else()
      set(_roscpp_ok OFF)
    endif()
  endforeach()
  find_package(Boost QUIET COMPONENTS filesystem system thread chrono)
  # Service headers are generated at build time with gencpp; its Python modules are Debian's, so
  # the interpreter is the system one, whatever python3 comes first on PATH.
  find_program(MULTICUE_GENCPP gen_cpp.py PATHS /usr/lib/gencpp NO_DEFAULT_PATH)
  find_path(MULTICUE_GENCPP_TEMPLATES srv.h.template PATHS /usr/share/gencpp NO_DEFAULT_PATH)
  set(MULTICUE_ROS_PYTHON "")
  foreach(_py IN ITEMS /usr/bin/python3 python3)
    execute_process(COMMAND ${_py} -c "import genmsg, gencpp" RESULT_VARIABLE _py_rc
                    OUTPUT_QUIET ERROR_QUIET)
    if(_py_rc EQUAL 0)
      set(MULTICUE_ROS_PYTHON ${_py})
      break()
    endif()
  endforeach()
  if(_roscpp_ok AND MULTICUE_ROSCPP_INCLUDE_DIR AND MULTICUE_SENSOR_MSGS_INCLUDE_DIR
     AND MULTICUE_VIS_MSGS_INCLUDE_DIR AND MULTICUE_STD_MSGS_INCLUDE_DIR AND Boost_FOUND
     AND MULTICUE_GENCPP AND MULTICUE_GENCPP_TEMPLATES AND MULTICUE_ROS_PYTHON)
    add_library(multicue_roscpp_deps INTERFACE)
    target_include_directories(multicue_roscpp_deps SYSTEM INTERFACE
                               ${MULTICUE_ROSCPP_INCLUDE_DIR} ${Boost_INCLUDE_DIRS})
    target_link_libraries(multicue_roscpp_deps INTERFACE ${_roscpp_found_libs} Boost::filesystem
                          Boost::system Boost::thread Boost::chrono)
    set(MULTICUE_ROSCPP_FOUND ON)
  endif()
  if(MULTICUE_ROS STREQUAL "ON" AND NOT (MULTICUE_ROS1_BAG_FOUND AND MULTICUE_ROSCPP_FOUND))
    message(FATAL_ERROR "MULTICUE_ROS=ON needs Debian's ROS 1 packages (librosbag-dev, "
                        "libroscpp-dev, libsensor-msgs-dev, libvisualization-msgs-dev, "
                        "python3-gencpp: scripts/setup.sh)")
  endif()
endif()
