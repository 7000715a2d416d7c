# Helpers shared by every module.

# Warnings for our own code (third-party headers are included as SYSTEM).
function(likeness_warnings target)
  # -Wshadow=local is GCC's; clang (emcc, the wasm build of the same code)
  # does not know it and would warn about the flag on every file.
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic
    $<$<CXX_COMPILER_ID:GNU>:-Wshadow=local>
    -Wno-missing-field-initializers)
endfunction()

# likeness_module(NAME name SOURCES a.cpp ... DEPS other_module ...)
# One static library per pipeline stage: lk_<name>. Headers are included as
# "<name>/<header>.h" relative to core/. Every module is also gathered into the
# interface target likeness_core.
function(likeness_module)
  cmake_parse_arguments(M "" "NAME" "SOURCES;DEPS;LIBS" ${ARGN})
  add_library(lk_${M_NAME} STATIC ${M_SOURCES})
  target_include_directories(lk_${M_NAME} PUBLIC ${PROJECT_SOURCE_DIR}/core)
  target_link_libraries(lk_${M_NAME} PUBLIC lk_third_party ${M_LIBS})
  foreach(d ${M_DEPS})
    target_link_libraries(lk_${M_NAME} PUBLIC lk_${d})
  endforeach()
  likeness_warnings(lk_${M_NAME})
  set_property(GLOBAL APPEND PROPERTY LIKENESS_MODULES lk_${M_NAME})
endfunction()

# likeness_embed(OUT_CPP var SYMBOL_PREFIX name FILES f1 f2 ...)
# Turns files into a C++ source defining, for each file, a
#   const unsigned char <prefix>_<stem>[];  const unsigned long <prefix>_<stem>_size;
# so the core and the renderer need no file system at run time (wasm).
function(likeness_embed out_var prefix)
  set(out ${CMAKE_CURRENT_BINARY_DIR}/${prefix}_embedded.cpp)
  set(deps ${ARGN})
  # add_custom_command splits arguments at ';', so the list travels '|'-joined.
  string(REPLACE ";" "|" files_arg "${deps}")
  add_custom_command(OUTPUT ${out}
    COMMAND ${CMAKE_COMMAND} -DOUT=${out} -DPREFIX=${prefix} "-DFILES=${files_arg}"
            -P ${PROJECT_SOURCE_DIR}/cmake/embed_files.cmake
    DEPENDS ${deps} ${PROJECT_SOURCE_DIR}/cmake/embed_files.cmake
    COMMENT "Embedding ${prefix} files" VERBATIM)
  set(${out_var} ${out} PARENT_SCOPE)
endfunction()
