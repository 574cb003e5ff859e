# Sanitizer and fuzzer builds of multicue's own targets (libraries, CLI, tests, fuzz targets).
#
#   -DMULTICUE_SANITIZE=address,undefined   AddressSanitizer + UndefinedBehaviorSanitizer
#   -DMULTICUE_SANITIZE=thread              ThreadSanitizer
#   -DMULTICUE_BUILD_FUZZERS=ON             libFuzzer programs in fuzz/ (clang; implies
#                                           address,undefined unless MULTICUE_SANITIZE says otherwise)
#
# The flags are directory-wide from here down, so they reach every target of this project and no
# third-party code (Debian's libraries stay as they are). Any report aborts the program: a test
# that triggers one fails. scripts/sanitize_ci.sh and scripts/fuzz.sh use these builds.
set(MULTICUE_SANITIZE "" CACHE STRING
    "Sanitizers for multicue's targets: address,undefined or thread (empty: none)")
option(MULTICUE_BUILD_FUZZERS "Build the libFuzzer programs in fuzz/ (needs clang)" OFF)

if(MULTICUE_BUILD_FUZZERS)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "MULTICUE_BUILD_FUZZERS=ON needs clang (libFuzzer): configure with "
                        "-DCMAKE_CXX_COMPILER=clang++ (Debian: clang-14, libclang-rt-14-dev)")
  endif()
  if(MULTICUE_SANITIZE STREQUAL "")
    set(MULTICUE_SANITIZE "address,undefined" CACHE STRING "" FORCE)
  endif()
  # Coverage instrumentation for every object; the fuzz programs link libFuzzer's main.
  add_compile_options(-fsanitize=fuzzer-no-link)
  add_link_options(-fsanitize=fuzzer-no-link)
endif()

if(NOT MULTICUE_SANITIZE STREQUAL "")
  string(REPLACE "," ";" _multicue_sanitizers "${MULTICUE_SANITIZE}")
  foreach(_s IN LISTS _multicue_sanitizers)
    if(NOT _s MATCHES "^(address|undefined|thread|leak)$")
      message(FATAL_ERROR "MULTICUE_SANITIZE: unknown sanitizer '${_s}' (address, undefined, "
                          "thread, leak)")
    endif()
  endforeach()
  if("thread" IN_LIST _multicue_sanitizers AND "address" IN_LIST _multicue_sanitizers)
    message(FATAL_ERROR "MULTICUE_SANITIZE: thread and address cannot be combined")
  endif()
  message(STATUS "Sanitizers on multicue's targets: ${MULTICUE_SANITIZE}")
  add_compile_options(-fsanitize=${MULTICUE_SANITIZE} -fno-omit-frame-pointer)
  add_link_options(-fsanitize=${MULTICUE_SANITIZE})
  if("undefined" IN_LIST _multicue_sanitizers)
    # A report is an error (abort), not a line in a log; the float-to-integer range check is part
    # of clang's "undefined" and asked for explicitly from gcc.
    if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
      add_compile_options(-fsanitize=float-cast-overflow)
      add_link_options(-fsanitize=float-cast-overflow)
    endif()
    add_compile_options(-fno-sanitize-recover=all)
  endif()
  if("thread" IN_LIST _multicue_sanitizers)
    # TBB's scheduler is not instrumented: core/parallel.hpp tells ThreadSanitizer where its
    # tasks start and end (MULTICUE_TSAN_ANNOTATIONS).
    add_compile_definitions(MULTICUE_TSAN_ANNOTATIONS=1)
  endif()
endif()
