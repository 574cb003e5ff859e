# multicue_peer_segmentation: PCL's table-top segmentation pipelines (eval/peers/), the peers of
# mosd_peers (accuracy) and bench_perceive (speed). Only with -DMULTICUE_BENCH_PEERS=ON; the
# including folder has found the peers (FindPeers.cmake) first.
if(NOT TARGET multicue_peer_segmentation)
  add_library(multicue_peer_segmentation STATIC ${PROJECT_SOURCE_DIR}/eval/peers/segmentation.cpp)
  target_include_directories(multicue_peer_segmentation PUBLIC ${PROJECT_SOURCE_DIR}/eval)
  target_link_libraries(multicue_peer_segmentation PUBLIC multicue_bench_peers)
  multicue_warnings(multicue_peer_segmentation)
endif()
