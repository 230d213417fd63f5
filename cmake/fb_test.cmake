# fb_test: one test, its labels and what it needs, in one call (tests/CMakeLists.txt):
#
#   fb_test(NAME name COMMAND program args...
#           | NAME name PROGRAM test_x.c LINK library... [ARGS args...]
#                                # the program test_x built from test_x.c, linked (PRIVATE) to the
#                                # libraries it tests, and run with ARGS
#           LABELS label...      # at least one: unit, cli, build or fuzz; and quick for the quick tier
#           [GPU]                # it needs a Vulkan device: label gpu, the validation layer on, and exit
#                                # 77 reported as not run where no device exists; and a twin,
#                                # NAME-staging, that runs it again on a discrete GPU's path
#                                # (FB_VK_STAGING=1: device-local memory, staging copies and the
#                                # portable exact arithmetic), so that lavapipe tests that path too,
#                                # under the layer's synchronization validation as well
#           [VULKAN]             # it may open a Vulkan device (it runs without one too): the validation
#                                # layer on, no gpu label
#           [SKIPPABLE]          # exit 77 reported as not run (it cannot run here: no AVX2, no clang,
#                                # no Vulkan device for a part that needs one)
#           [ENV VAR=value...]   # more of its environment
#           [TIMEOUT seconds])   # CTest's default (1500) otherwise
#
# The labels are the tiers: `ctest -L quick` is every test labelled quick (a test of every room
# between edits, under a minute in all on two cores), `ctest -L gpu` every test that needs a device,
# `ctest` everything, as CI runs it. A label outside the list below fails the configure, so a typo
# cannot drop a test from its tier.
set(FB_TEST_LABELS unit cli build fuzz quick)
# The staging twins run with the validation layer's synchronization checks too (the layer reads
# VK_LAYER_ENABLES itself): the discrete path's copies and barriers are where a real GPU reorders.
set(FB_VK_SYNC_VALIDATION VK_LAYER_ENABLES=VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT)

function(fb_test)
  cmake_parse_arguments(PARSE_ARGV 0 T "GPU;VULKAN;SKIPPABLE" "NAME;TIMEOUT;PROGRAM" "COMMAND;LABELS;ENV;LINK;ARGS")
  if(T_UNPARSED_ARGUMENTS OR NOT T_NAME OR (T_COMMAND AND T_PROGRAM) OR NOT (T_COMMAND OR (T_PROGRAM AND T_LINK)))
    message(FATAL_ERROR "fb_test(${T_NAME}): NAME and either COMMAND or PROGRAM with LINK are needed; "
                        "unexpected: ${T_UNPARSED_ARGUMENTS}")
  endif()
  if(T_PROGRAM)
    get_filename_component(exe ${T_PROGRAM} NAME_WE)
    add_executable(${exe} ${T_PROGRAM})
    target_link_libraries(${exe} PRIVATE ${T_LINK})
    set(T_COMMAND ${exe} ${T_ARGS})
  endif()
  set(kinds 0)
  foreach(l ${T_LABELS})
    if(NOT l IN_LIST FB_TEST_LABELS)
      message(FATAL_ERROR "fb_test(${T_NAME}): label '${l}' is not one of ${FB_TEST_LABELS} (GPU adds gpu)")
    endif()
    if(NOT l STREQUAL quick)
      math(EXPR kinds "${kinds} + 1")
    endif()
  endforeach()
  if(kinds EQUAL 0 AND NOT T_GPU)
    message(FATAL_ERROR "fb_test(${T_NAME}): LABELS needs one of unit, cli, build or fuzz (or GPU)")
  endif()
  set(labels ${T_LABELS})
  set(env ${T_ENV})
  if(T_GPU)
    list(PREPEND labels gpu)
  endif()
  add_test(NAME ${T_NAME} COMMAND ${T_COMMAND})
  set_tests_properties(${T_NAME} PROPERTIES LABELS "${labels}")
  if(T_GPU OR T_VULKAN)
    list(APPEND env FB_VK_VALIDATION=1)
  endif()
  if(T_GPU OR T_SKIPPABLE)
    set_tests_properties(${T_NAME} PROPERTIES SKIP_RETURN_CODE 77)
  endif()
  if(env)
    set_tests_properties(${T_NAME} PROPERTIES ENVIRONMENT "${env}")
  endif()
  if(T_TIMEOUT)
    set_tests_properties(${T_NAME} PROPERTIES TIMEOUT ${T_TIMEOUT})
  endif()
  if(T_GPU)
    add_test(NAME ${T_NAME}-staging COMMAND ${T_COMMAND})
    set_tests_properties(${T_NAME}-staging PROPERTIES LABELS "gpu;staging" SKIP_RETURN_CODE 77
                                                      ENVIRONMENT "${env};FB_VK_STAGING=1;${FB_VK_SYNC_VALIDATION}")
    if(T_TIMEOUT)
      set_tests_properties(${T_NAME}-staging PROPERTIES TIMEOUT ${T_TIMEOUT})
    endif()
  endif()
endfunction()
