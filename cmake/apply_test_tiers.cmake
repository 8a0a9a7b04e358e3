# Run by ctest, after the GoogleTest suites' discovered tests are defined
# (CMakeLists.txt adds it to TEST_INCLUDE_FILES after them): gives every
# test its tier label from tests/tiers.cmake, the suite's name as a second
# label, slow_under_sanitizers where tests/tiers.cmake says so, and the
# simulator's render threads as the processors ctest gives the test.
#
# A test that no rule and no suite default places, or a rule that places no
# test (a renamed test), makes Tiers.EveryTestHasOneTier fail, naming them.
#
# Set by CMakeLists.txt when it writes this file's caller:
#   PROBELIGHT_TIER_RULES    tests/tiers.cmake
#   PROBELIGHT_TEST_SUITES   the suites (test_<suite>_TESTS lists their tests)

set(probelight_tier_names unit gpu e2e accuracy vm)
set(probelight_tier_rule_count 0)
set(probelight_slow_rule_count 0)
set(probelight_slow_rules)

# probelight_suite_tier(SUITE TIER): the tier of SUITE's tests that no rule names.
function(probelight_suite_tier suite tier)
  set(PROBELIGHT_SUITE_TIER_${suite} ${tier} PARENT_SCOPE)
endfunction()

# probelight_tier(TIER SUITE FIXTURE...): the tests of these GoogleTest
# fixtures (and their parameterised instances) in SUITE are in TIER.
macro(probelight_tier tier suite)
  _probelight_tier_rule(FIXTURES ${tier} ${suite} ${ARGN})
endmacro()

# probelight_test_tier(TIER SUITE TEST...): these whole test names (without
# a parameter suffix, which is matched as any) are in TIER; before fixtures.
macro(probelight_test_tier tier suite)
  _probelight_tier_rule(TESTS ${tier} ${suite} ${ARGN})
endmacro()

function(_probelight_tier_rule kind tier suite)
  set(names)
  foreach(name IN LISTS ARGN)
    string(REPLACE "." "\\." name "${name}")
    list(APPEND names "${name}")
  endforeach()
  list(JOIN names "|" alternatives)
  math(EXPR n "${probelight_tier_rule_count} + 1")
  set(probelight_tier_rule_count ${n} PARENT_SCOPE)
  set(PROBELIGHT_TIER_RULE_${n}_TIER ${tier} PARENT_SCOPE)
  set(PROBELIGHT_TIER_RULE_${n}_SUITE ${suite} PARENT_SCOPE)
  set(PROBELIGHT_TIER_RULE_${n}_TEXT "${tier} ${suite} ${ARGN}" PARENT_SCOPE)
  if(kind STREQUAL "TESTS")
    set(PROBELIGHT_TIER_RULE_${n}_REGEX "^([A-Za-z0-9_]+/)?(${alternatives})(/.*)?$" PARENT_SCOPE)
    set(PROBELIGHT_TIER_RULE_${n}_FIRST ON PARENT_SCOPE)
  else()
    set(PROBELIGHT_TIER_RULE_${n}_REGEX "^([A-Za-z0-9_]+/)?(${alternatives})\\." PARENT_SCOPE)
  endif()
endfunction()

# probelight_slow_under_sanitizers(SUITE TEST_REGEX REASON): SUITE's tests
# whose names match are labelled slow_under_sanitizers, which
# scripts/test-sanitizers.sh leaves to the release run.
function(probelight_slow_under_sanitizers suite regex reason)
  math(EXPR n "${probelight_slow_rule_count} + 1")
  set(probelight_slow_rule_count ${n} PARENT_SCOPE)
  set(probelight_slow_rules ${probelight_slow_rules} ${n} PARENT_SCOPE)
  set(PROBELIGHT_SLOW_RULE_${n}_SUITE ${suite} PARENT_SCOPE)
  set(PROBELIGHT_SLOW_RULE_${n}_REGEX "${regex}" PARENT_SCOPE)
endfunction()

include("${PROBELIGHT_TIER_RULES}")
if(probelight_tier_rule_count EQUAL 0)
  message(FATAL_ERROR "${PROBELIGHT_TIER_RULES}: no probelight_tier rules")
endif()

set(probelight_tier_problems)
set(probelight_rule_hits)
foreach(suite IN LISTS PROBELIGHT_TEST_SUITES)
  foreach(test IN LISTS test_${suite}_TESTS)
    set(tier "")
    # Whole-test rules first, then fixture rules, then the suite's default.
    foreach(pass FIRST FIXTURE)
      if(tier STREQUAL "")
        foreach(n RANGE 1 ${probelight_tier_rule_count})
          if(pass STREQUAL "FIRST" AND NOT PROBELIGHT_TIER_RULE_${n}_FIRST)
            continue()
          endif()
          if(pass STREQUAL "FIXTURE" AND PROBELIGHT_TIER_RULE_${n}_FIRST)
            continue()
          endif()
          if(PROBELIGHT_TIER_RULE_${n}_SUITE STREQUAL suite AND test MATCHES "${PROBELIGHT_TIER_RULE_${n}_REGEX}")
            set(tier ${PROBELIGHT_TIER_RULE_${n}_TIER})
            list(APPEND probelight_rule_hits ${n})
            break()
          endif()
        endforeach()
      endif()
    endforeach()
    if(tier STREQUAL "")
      set(tier "${PROBELIGHT_SUITE_TIER_${suite}}")
    endif()
    if(NOT tier IN_LIST probelight_tier_names)
      list(APPEND probelight_tier_problems "no tier: ${suite} ${test}")
      set(tier untiered)
    endif()
    set(labels ${tier} ${suite})
    foreach(n IN LISTS probelight_slow_rules)
      if(PROBELIGHT_SLOW_RULE_${n}_SUITE STREQUAL suite AND test MATCHES "${PROBELIGHT_SLOW_RULE_${n}_REGEX}")
        list(APPEND labels slow_under_sanitizers)
        list(APPEND probelight_rule_hits slow${n})
        break()
      endif()
    endforeach()
    # One processor each (ctest's default), so one render thread each.
    set_tests_properties("${test}" PROPERTIES LABELS "${labels}" PROCESSORS 1
                         ENVIRONMENT "PROBELIGHT_SIM_THREADS=1")
  endforeach()
endforeach()
# (A rule for a suite this build leaves out names none here.)
foreach(n RANGE 1 ${probelight_tier_rule_count})
  if(NOT n IN_LIST probelight_rule_hits AND PROBELIGHT_TIER_RULE_${n}_SUITE IN_LIST PROBELIGHT_TEST_SUITES)
    list(APPEND probelight_tier_problems "a rule that names no test: ${PROBELIGHT_TIER_RULE_${n}_TEXT}")
  endif()
endforeach()
foreach(n IN LISTS probelight_slow_rules)
  if(NOT "slow${n}" IN_LIST probelight_rule_hits AND PROBELIGHT_SLOW_RULE_${n}_SUITE IN_LIST PROBELIGHT_TEST_SUITES)
    list(APPEND probelight_tier_problems "a slow_under_sanitizers rule that names no test: ${PROBELIGHT_SLOW_RULE_${n}_REGEX}")
  endif()
endforeach()

if(probelight_tier_problems)
  list(JOIN probelight_tier_problems "\n" problem_text)
  string(REPLACE "'" "" problem_text "${problem_text}")
  add_test(Tiers.EveryTestHasOneTier /bin/sh -c "printf '%s\\n' '${problem_text}' >&2; exit 1")
else()
  add_test(Tiers.EveryTestHasOneTier /bin/sh -c "echo 'every test has one tier; every rule names a test'")
endif()
set_tests_properties(Tiers.EveryTestHasOneTier PROPERTIES LABELS "unit")
