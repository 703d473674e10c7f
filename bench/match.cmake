# Match evaluation (issue 6): synthetic recovery and photos; see bench/match_eval.cpp.
if(TARGET proctex_catalog)
  add_executable(bench_match_eval ${CMAKE_CURRENT_LIST_DIR}/match_eval.cpp)
  target_link_libraries(bench_match_eval PRIVATE proctex_search fmt::fmt)
endif()
# Shader selection evidence (issue 12): group distances of labelled photos to the catalogue.
if(TARGET proctex_catalog)
  add_executable(bench_select_dump ${CMAKE_CURRENT_LIST_DIR}/select_dump.cpp)
  target_link_libraries(bench_select_dump PRIVATE proctex_search proctex_shaders fmt::fmt)
endif()
