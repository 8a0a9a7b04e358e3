# Every test's tier, a ctest label (cmake/apply_test_tiers.cmake applies
# these when ctest runs; a test placed nowhere, or a rule that names no
# test, fails Tiers.EveryTestHasOneTier):
#
#   unit      pure CPU: no GL context, no simulator render, no run of the
#             binary; each well under a second (0.01-0.8 s here)
#   gpu       GLES2 passes on Mesa against their CPU references
#   e2e       the probelight binary through its commands
#   accuracy  numbers against a slow truth: the simulator's renders and
#             path tracing, or a brute-force integral or exhaustive sweep
#             that takes over a second
#   vm        the .deb and the board VM's host-side checks (CMakeLists.txt)
#
# scripts/test.sh runs them all, tier by tier; --quick runs unit and gpu.
# scripts/test-sanitizers.sh runs every test under ASan and UBSan but the
# vm tier and the tests labelled slow_under_sanitizers at the end of this
# file: every unit, gpu and e2e test, and the accuracy tier's checks of the
# product's code (the tracker, the stages, the passes) on simulated frames.
#
# A suite's default tier, then the fixtures (and single tests) that differ.

probelight_suite_tier(accuracy accuracy)
probelight_suite_tier(app e2e)
probelight_suite_tier(capture unit)
probelight_suite_tier(gles gpu)
probelight_suite_tier(ibl unit)
probelight_suite_tier(model unit)
probelight_suite_tier(sim accuracy)
probelight_suite_tier(stages unit)
probelight_suite_tier(tracking unit)

# app: the pure units beside the binary's tests.
probelight_tier(unit app AppSettings ButtonDebouncer ButtonFactory CalibrationOutliers CommandLine FuzzRegressions
                GpioButton GpioLines HeapRelease HeapReleasePolicy ImageWriteQueue KeyButton KeyLineReader KmsModes
                Letterbox LibcameraSource ReconnectBackoff StatusLed WindowKeys)

# gles: the CPU halves of the passes (geometry, weights, the shaders' 16-bit
# twins) that make no context.
probelight_tier(unit gles CasterTriangles DarkeningCells DiffuseSeamsMeasure EdgeAntialiasing ExtensionList
                DmabufImportCheck GlesVersion HalfFloatRoute MediumpTwins ModelTextures MotionSmearTaps ObjectBloom ObjectBlurWeights ReflectionRungs
                SensorNoiseTexels SphereTessellation)
# ... but for sweeps of every pixel of a frame or every code (1.7-4 s).
probelight_test_tier(accuracy gles MediumpTwins.GroundCompositeAt16BitsMovesTheCameraSampleByUnderAPixel
                     MediumpTwins.YuvPlanesConvertWithinALevelAt16Bits ShadowFootprint.HoldsEveryGroundPointTheLightsConeCanHide)

# ibl: a brute-force integral of a zenith lamp (3.8 s).
probelight_test_tier(accuracy ibl GlossyMaps.ZenithLampAgainstBruteForceWithAndWithoutPoleCorrection)

# sim: the simulator's own pure parts (names, paths, scene checks, its BVH
# and BRDF maths) are units; what renders is accuracy.
probelight_tier(unit sim CameraPath CameraPaths DefaultScene GltfBrdf LatLong LensBlurKernel Names RandomPoses
                RealHdrWorlds SceneErrors TriangleBvh)
probelight_test_tier(accuracy sim GltfBrdf.ImportanceSamplingMatchesQuadrature
                     GltfBrdf.WhiteFurnaceMetalsSendBackAtMostWhatComesIn
                     TriangleBvh.EngineClosestHitIsWhatEveryTriangleGives)

# stages: the noise and edge-blur measurements on simulator renders.
probelight_tier(accuracy stages EdgeBlur EdgeBlurAtSetting SensorNoise SensorNoiseAtSetting)

# tracking: the tracker and pose on simulator renders, and the smoother's
# statistics over long sequences (up to 6.7 s).
probelight_tier(accuracy tracking PoseAccuracy PoseSmoother ProbeEdgeFit TagTrackerStatus TagTrackerSynthetic
                TagTrackerWindow)

# Too slow under the sanitizers: left to the release run, each with why
# and what runs its code there. (The simulator itself is built without
# instrumentation there: CMakeLists.txt says why.)
#
# tests/accuracy: the pipeline against path-traced truth over many views,
# worlds and models. Its path tracing is the test's own (uninstrumented or
# not, 1470 of the sanitizer run's 3400 test-seconds in CI of 2026-12-05);
# the code it runs (the stages, the passes, analyze and run through the
# binary) runs under the sanitizers in the e2e, gpu and unit tiers.
probelight_slow_under_sanitizers(accuracy ".*" "path-traced truth over many views and models")
