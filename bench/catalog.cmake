# Catalogue benchmark (included by bench/CMakeLists.txt when present).
if(TARGET proctex_catalog)
  add_executable(bench_catalog ${CMAKE_CURRENT_LIST_DIR}/catalog_bench.cpp)
  target_link_libraries(bench_catalog PRIVATE proctex_catalog fmt::fmt)
endif()
