# Furniture detection by part configurations (thesis section 4.2): CAD model fitting and
# verification, the detection pipeline over registered scans. Included after mapping/.
target_sources(multicue_mapping PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/furniture_fit.cpp
  ${CMAKE_CURRENT_LIST_DIR}/furniture_detection.cpp)
target_link_libraries(multicue_mapping PUBLIC multicue::recognition multicue::registration
                      PRIVATE multicue::filters)
