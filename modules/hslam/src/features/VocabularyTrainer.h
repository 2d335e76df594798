/*
 * H-SLAM for ViSP.
 */
/*!
  \file VocabularyTrainer.h
  \brief Training of an OrbVocabulary: hierarchical k-means over binary descriptors, then IDF word weights.

  What it is for: no usable ORB vocabulary can be downloaded here, so the project trains its own (the shipped one
  and any a user trains on their own images with tutorial-hslam-vocabulary).

  The algorithm is DBoW2's: the descriptors of every training image are clustered into k groups by k-means with
  k-means++ seeding, each group again into k, down to L levels; a group of k descriptors or fewer is not split
  (each descriptor becomes a leaf) and a group of one stops. Centroids of binary descriptors are bit majorities
  (a bit is set when more than half of the group has it). The leaves are the words; a word's weight is
  log(N / N_i) for TF-IDF and IDF (N training images, N_i of them having at least one descriptor that descends to
  the word), 1 for TF and binary.

  Determinism: the result depends only on the descriptors (in image order), the options and the seed. Random
  choices come from a counter-based generator seeded by (seed, node), never from std::random distributions, whose
  output differs between standard libraries; the same inputs give a byte-identical file on any machine.

  Threading: train() runs in the caller's thread.
*/
#ifndef HSLAM_FEATURES_VOCABULARY_TRAINER_H
#define HSLAM_FEATURES_VOCABULARY_TRAINER_H

#include "features/OrbVocabulary.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace hslam
{
//! Settings of the training.
struct VocabularyTrainingOptions {
  int branching = 10; //!< k, children per node (DBoW2 / ORB-SLAM2: 10)
  int levels = 6;     //!< L, depth of the tree: up to k^L words (ORB-SLAM2: 6)
  VocabularyWeighting weighting = VocabularyWeighting::tfIdf;
  std::uint64_t seed = 1;       //!< k-means++ seeding
  int maxKmeansIterations = 30; //!< cap on Lloyd iterations per node (DBoW2 iterates to convergence)
};

/*!
  Train a vocabulary.
  \param images : descriptors of each training image (images without descriptors are allowed and count in N).
  \param options : see VocabularyTrainingOptions.
  \param progress : optional, called with the fraction done in [0, 1] from the caller's thread.
  \exception vpHSlamException::invalidArgument on bad options or when there are fewer than k descriptors.
*/
VISP_EXPORT OrbVocabulary trainVocabulary(const std::vector<std::vector<OrbDescriptor>> &images,
                                          const VocabularyTrainingOptions &options,
                                          const std::function<void(double)> &progress = std::function<void(double)>());
} // namespace hslam

#endif
