# RGBN benchmarks (included by bench/CMakeLists.txt when present).
if(TARGET proctex_rgbn)
  add_executable(bench_rgbn ${CMAKE_CURRENT_LIST_DIR}/rgbn_bench.cpp)
  target_link_libraries(bench_rgbn PRIVATE proctex_rgbn benchmark::benchmark)
  target_compile_definitions(bench_rgbn PRIVATE PROCTEX_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared")
  add_executable(bench_rgbn_mip ${CMAKE_CURRENT_LIST_DIR}/rgbn_mip_bench.cpp)
  target_link_libraries(bench_rgbn_mip PRIVATE proctex_rgbn)
  target_compile_definitions(bench_rgbn_mip PRIVATE PROCTEX_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared")
endif()
