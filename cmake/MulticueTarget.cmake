# Warning flags for multicue's own targets only; third-party headers are included as SYSTEM.
function(multicue_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor)
  if(MULTICUE_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# multicue_module(NAME SOURCES ... DEPS ...): one library target per module, multicue::NAME.
function(multicue_module name)
  cmake_parse_arguments(M "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(multicue_${name} ${M_SOURCES})
  add_library(multicue::${name} ALIAS multicue_${name})
  target_include_directories(multicue_${name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>)
  target_link_libraries(multicue_${name} PUBLIC ${M_DEPS} PRIVATE ${M_PRIVATE_DEPS})
  set_target_properties(multicue_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  multicue_warnings(multicue_${name})
endfunction()
