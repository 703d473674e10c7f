# Metric benchmarks (included by bench/CMakeLists.txt when present).
if(TARGET proctex_metrics)
  add_executable(bench_metrics_retrieval ${CMAKE_CURRENT_LIST_DIR}/metrics_retrieval.cpp)
  target_link_libraries(bench_metrics_retrieval PRIVATE proctex_metrics)
  target_compile_definitions(bench_metrics_retrieval PRIVATE
    PROCTEX_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared")
  if(TARGET proctex_shaders)
    target_link_libraries(bench_metrics_retrieval PRIVATE proctex_shaders)
    target_compile_definitions(bench_metrics_retrieval PRIVATE PROCTEX_BENCH_SHADERS)
  endif()
  if(TARGET benchmark::benchmark)
    add_executable(bench_metrics ${CMAKE_CURRENT_LIST_DIR}/metrics_bench.cpp)
    target_link_libraries(bench_metrics PRIVATE proctex_metrics benchmark::benchmark)
    target_compile_definitions(bench_metrics PRIVATE
      PROCTEX_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared")
  endif()
endif()
