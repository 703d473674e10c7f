# Service benchmark (included by bench/CMakeLists.txt when present): slider renders while a match
# runs, first live preview, service vs command-line match time. Runs the proctex binary too.
if(TARGET proctex_server)
  add_executable(bench_serve ${CMAKE_CURRENT_LIST_DIR}/serve_bench.cpp)
  target_link_libraries(bench_serve PRIVATE proctex_server fmt::fmt nlohmann_json::nlohmann_json)
  target_compile_definitions(bench_serve PRIVATE PROCTEX_BINARY="$<TARGET_FILE:proctex>"
                             PROCTEX_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  add_dependencies(bench_serve proctex)
endif()
