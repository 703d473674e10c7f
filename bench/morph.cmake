# Morph benchmark (included by bench/CMakeLists.txt when present): runs the proctex binary.
if(TARGET proctex_transform)
  add_executable(bench_morph ${CMAKE_CURRENT_LIST_DIR}/morph_bench.cpp)
  target_link_libraries(bench_morph PRIVATE proctex_catalog fmt::fmt nlohmann_json::nlohmann_json)
  target_compile_definitions(bench_morph PRIVATE PROCTEX_BINARY="$<TARGET_FILE:proctex>")
  add_dependencies(bench_morph proctex)
endif()
