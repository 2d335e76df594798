/*
 * H-SLAM for ViSP.
 */
/*!
  \file BowVector.h
  \brief Bag-of-words vectors and the direct index (features grouped by vocabulary node) of one image.

  Both are flat vectors sorted by id, not maps: a keyframe's BoW vector has a few hundred to two thousand entries
  and is only ever walked in order (scores, inverted-index updates, matching by node), which sorted arrays do
  faster and with one allocation.
*/
#ifndef HSLAM_FEATURES_BOW_VECTOR_H
#define HSLAM_FEATURES_BOW_VECTOR_H

#include <cstdint>
#include <utility>
#include <vector>

namespace hslam
{
//! One word of a BoW vector: word id and its weight (TF-IDF by default; L1-normalised over the vector).
struct BowEntry {
  std::uint32_t wordId;
  double weight;
  bool operator==(const BowEntry &other) const { return wordId == other.wordId && weight == other.weight; }
};

//! A bag-of-words vector: entries sorted by strictly increasing word id, weights summing to 1 (or empty).
using BowVector = std::vector<BowEntry>;

//! Direct index: for each vocabulary node of the chosen level, the indices of the image's features under it.
struct FeatureGroup {
  std::uint32_t nodeId;
  std::vector<std::uint32_t> features; //!< indices into the descriptor list given to the transform, increasing
  bool operator==(const FeatureGroup &other) const { return nodeId == other.nodeId && features == other.features; }
};

//! Groups sorted by strictly increasing node id.
using FeatureVector = std::vector<FeatureGroup>;
} // namespace hslam

#endif
