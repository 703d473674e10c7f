# Exemplar synthesis vs G'MIC (issue 13): see bench/synth_bench.cpp and docs/synth.md.
if(TARGET proctex_synth AND TARGET proctex_metrics)
  find_package(Eigen3 REQUIRED NO_MODULE)
  add_executable(bench_synth ${CMAKE_CURRENT_LIST_DIR}/synth_bench.cpp)
  target_link_libraries(bench_synth PRIVATE proctex_synth proctex_metrics Eigen3::Eigen fmt::fmt)
endif()
