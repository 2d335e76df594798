/*
 * H-SLAM for ViSP.
 */
/*!
  \file LoopSolverOptions.h
  \brief The Ceres settings every loop-closure problem shares (private to loop/: Sim3Solver, PoseGraph,
  GlobalBundleAdjustment), so the three solvers cannot drift apart on the back-end, the threads or the output.
*/
#ifndef HSLAM_LOOP_LOOP_SOLVER_OPTIONS_H
#define HSLAM_LOOP_LOOP_SOLVER_OPTIONS_H

#include <ceres/solver.h>

namespace hslam
{
/*!
  Sparse Cholesky back-end of every loop-closure problem: Eigen's. SuiteSparse's CHOLMOD, Ceres' default, runs its
  supernodal factorisation on an OpenMP pool whatever Ceres' num_threads says, so a correction would take cores from
  tracking, and its pool is invisible to ThreadSanitizer; the problems here (a few hundred keyframes) are small.
*/
constexpr ceres::SparseLinearAlgebraLibraryType kLoopSparseLibrary = ceres::EIGEN_SPARSE;

/*!
  Solver settings of a loop-closure problem: the given iterations and linear solver, kLoopSparseLibrary, one thread
  (the mapping thread's core; a caller that owns more sets num_threads itself), no output.
*/
inline ceres::Solver::Options loopSolverOptions(int maxIterations, ceres::LinearSolverType linearSolver)
{
  ceres::Solver::Options options;
  options.max_num_iterations = maxIterations;
  options.linear_solver_type = linearSolver;
  options.sparse_linear_algebra_library_type = kLoopSparseLibrary;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  return options;
}
} // namespace hslam

#endif
