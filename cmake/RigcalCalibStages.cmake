# SPDX-License-Identifier: Apache-2.0
# The stages of the calibration method in calib/src/<stage>/, lowest first: a stage uses only
# itself and the stages before it, so calib's include drawing has no arrow running back up.
# Checked by tests/architecture/check_stages.cmake:
#  - a source of a stage includes the private headers (by path from calib/src:
#    "models/planar_solver.h") of its own stage or lower ones only, and public headers
#    (rigcal/calib/<file>.h) of the foundation or of its own stage or lower ones;
#  - the sources at calib/src's root belong to the foundation: they include no private header
#    and no stage's public header;
#  - a public header includes no private header, and no public header of a higher stage (a
#    header of the foundation none of any stage);
#  - every folder in calib/src is a stage.
# The foundation, below every stage: the public headers no stage names (the options, results
# and states every stage speaks, the error model, the synthetic generators) and their sources
# at calib/src's root.
#   rigcal_calib_stage(<stage> [PUBLIC <the headers in calib/include/rigcal/calib/ it declares>])
set(RIGCAL_CALIB_STAGES "")
macro(rigcal_calib_stage name)
  cmake_parse_arguments(RIGCAL_CALIB_STAGE_ARG "" "" "PUBLIC" ${ARGN})
  list(APPEND RIGCAL_CALIB_STAGES ${name})
  set(RIGCAL_CALIB_STAGE_PUBLIC_${name} ${RIGCAL_CALIB_STAGE_ARG_PUBLIC})
endmacro()

# The cameras' poses matched in time: the sync buffer, the lossless pipelines' pose merge, the
# poses and clock offsets of cameras that run free.
rigcal_calib_stage(sync PUBLIC sync_buffer.h pose_merge.h pose_interpolation.h clock_offset.h
                   clock_offset_tracker.h)
# From poses to motions: their working form, glitched poses (batch and online), the pairs of
# times (batch) and of keyframes (online).
rigcal_calib_stage(motions PUBLIC pair_selection.h)
# The linear solution (thesis 4.3, 4.5) and its sufficient statistics, the planar solver, which
# model the motions determine and its explanation, the scale measurements.
rigcal_calib_stage(models)
# How the errors are shared: the pose noise and its whitening, the regressor's noise, time
# blocks of motions and of rotation information, the Loewner maximum of covariances.
rigcal_calib_stage(noise PUBLIC noise_whitening.h)
# The refinements: non-linear least squares (thesis 4.4) and GLS on consecutive motions.
rigcal_calib_stage(refinement)
# The batch calibrator (CalibrateRig): its stages, from the motions to the accepted result.
rigcal_calib_stage(batch PUBLIC rig_calibrator.h)
# The recursive estimator (RigEstimator): its stages, the background refinement and the
# OnlineCalibrator's threads.
rigcal_calib_stage(online PUBLIC rig_estimator.h refinement_job.h online_calibrator.h)
