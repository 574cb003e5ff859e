# Warning flags for multicue's own targets only; third-party headers are included as SYSTEM.
function(multicue_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor)
  if(MULTICUE_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# multicue_module(NAME SOURCES ... DEPS ...): one library target per module, multicue::NAME.
# The target is exported as multicue::NAME too (cmake/MulticueInstall.cmake installs every module
# listed in the global property MULTICUE_MODULES). Headers are included as "multicue/NAME/x.hpp"
# from src/ in the build tree and from include/ once installed.
#
# With MULTICUE_BATCH_MODULES (the default) a module's source files compile in batches of five
# (cmake/MulticueBatches.cmake): a cold build of the library takes about half the compiler
# time. Files generated in the build folder and those listed after UNBATCHED compile on their own.
# Turn it off when editing one module's files over and over: a change then recompiles one file,
# not its batch.
option(MULTICUE_BATCH_MODULES "Compile each library module's files in batches of five" ON)

function(multicue_module name)
  cmake_parse_arguments(M "" "" "SOURCES;UNBATCHED;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(multicue_${name} ${M_SOURCES} ${M_UNBATCHED})
  if(MULTICUE_BATCH_MODULES)
    set(batched "")
    foreach(source IN LISTS M_SOURCES)
      get_filename_component(path ${source} ABSOLUTE BASE_DIR ${CMAKE_CURRENT_SOURCE_DIR})
      string(FIND "${path}" "${CMAKE_CURRENT_SOURCE_DIR}/" at)
      if(at EQUAL 0)
        list(APPEND batched ${source})
      endif()
    endforeach()
    multicue_compile_in_batches(multicue_${name} 5 ${batched})
  endif()
  add_library(multicue::${name} ALIAS multicue_${name})
  target_include_directories(multicue_${name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>
    $<BUILD_INTERFACE:${PROJECT_BINARY_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_compile_features(multicue_${name} PUBLIC cxx_std_20)
  target_link_libraries(multicue_${name} PUBLIC ${M_DEPS} PRIVATE ${M_PRIVATE_DEPS})
  set_target_properties(multicue_${name} PROPERTIES
    POSITION_INDEPENDENT_CODE ON
    EXPORT_NAME ${name}
    VERSION ${PROJECT_VERSION}
    SOVERSION ${MULTICUE_SOVERSION})
  multicue_warnings(multicue_${name})
  set_property(GLOBAL APPEND PROPERTY MULTICUE_MODULES multicue_${name})
endfunction()
