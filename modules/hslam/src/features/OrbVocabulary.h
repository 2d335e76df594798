/*
 * H-SLAM for ViSP.
 */
/*!
  \file OrbVocabulary.h
  \brief Hierarchical vocabulary tree over 256-bit ORB descriptors (DBoW2 model): descriptor to word, image to
  bag-of-words vector and direct index, and the L1 score between two vectors.

  What it is for: place recognition (relocalisation, loop detection; paper section 3.4, ARCHITECTURE.md "Loop
  closure") describes a keyframe by the histogram of the vocabulary words its ORB descriptors fall into, weighted
  by how rare each word is (TF-IDF), and compares keyframes by the L1 score `1 - 0.5 |v1 - v2|_1` of the
  L1-normalised histograms (Galvez-Lopez and Tardos, "Bags of binary words", T-RO 2012). The direct index groups the
  features by the node they pass a few levels above the leaves, so that descriptor matching between two keyframes
  only compares features under the same node (ORB-SLAM's SearchByBoW).

  Model, as DBoW2: node 0 is the root; every other node has a parent, a binary centroid and, when it is a leaf, a
  word id and a weight. A descriptor descends from the root to the child with the smallest Hamming distance (the
  first one on ties) until it reaches a leaf. The branching factor k and depth L are bounds (leaves may be
  shallower: clusters of k or fewer descriptors are not split during training).

  Weighting (DBoW2 numbering, kept so DBoW2 files load unchanged): TF-IDF and TF add the word weight once per
  feature, IDF and binary once per word; the vector is then L1-normalised. Words of weight 0 are skipped. Scoring
  is always L1 here; a DBoW2 file's scoring field is kept (and written back) but not used.

  Threading: immutable after assign(); every const method may be called from any number of threads.
*/
#ifndef HSLAM_FEATURES_ORB_VOCABULARY_H
#define HSLAM_FEATURES_ORB_VOCABULARY_H

#include "features/BinaryDescriptor.h"
#include "features/BowVector.h"

#include <visp3/core/vpConfig.h>

#include <cstdint>
#include <string>
#include <vector>

namespace hslam
{
//! How word weights are formed and accumulated (DBoW2's WeightingType numbering).
enum class VocabularyWeighting : int { tfIdf = 0, tf = 1, idf = 2, binary = 3 };

//! DBoW2's ScoringType numbering, kept for file round trips; H-SLAM scores with L1 whatever the file says.
enum class VocabularyScoring : int { l1 = 0, l2 = 1, chiSquare = 2, kl = 3, bhattacharyya = 4, dotProduct = 5 };

//! The vocabulary tree. Empty until assign() (the trainer and the file readers call it).
class VISP_EXPORT OrbVocabulary
{
public:
  static constexpr std::uint32_t kNoWord = 0xffffffffu;
  static constexpr int kMaxBranching = 255; //!< bounds checked on assign (DBoW2 files use k <= 20)
  static constexpr int kMaxLevels = 16;

  //! The whole tree in flat arrays, as trainers and readers produce it.
  struct Parts {
    int branching = 0; //!< k
    int levels = 0;    //!< L
    VocabularyWeighting weighting = VocabularyWeighting::tfIdf;
    VocabularyScoring scoring = VocabularyScoring::l1;
    std::vector<std::uint32_t> parents;     //!< parent of each node; entry 0 (the root) is ignored
    std::vector<OrbDescriptor> descriptors; //!< centroid of each node; entry 0 is ignored
    std::vector<std::uint32_t> wordNodes;   //!< node of each word
    std::vector<double> wordWeights;        //!< weight of each word
  };

  /*!
    Replace the tree. Checks that it is one: every node's parent precedes it (so the graph is a tree rooted at node
    0, as DBoW2 writes them), no node has more than k children or lies deeper than L, every leaf is exactly one word
    and every word a leaf, weights are finite and non-negative.
    \param origin : named in error messages (usually the file the parts were read from).
    \exception vpHSlamException::parseError when the parts do not form such a tree (the vocabulary is unchanged).
  */
  void assign(Parts parts, const std::string &origin);

  bool empty() const { return m_parents.empty(); }
  int branching() const { return m_branching; }
  int levels() const { return m_levels; }
  VocabularyWeighting weighting() const { return m_weighting; }
  VocabularyScoring scoring() const { return m_scoring; }
  std::size_t nodeCount() const { return m_parents.size(); }
  std::size_t wordCount() const { return m_wordNodes.size(); }

  std::uint32_t parent(std::uint32_t node) const { return m_parents[node]; }
  const OrbDescriptor &descriptor(std::uint32_t node) const { return m_childDescriptors[m_nodeSlots[node]]; }
  std::uint32_t wordNode(std::uint32_t word) const { return m_wordNodes[word]; }
  double wordWeight(std::uint32_t word) const { return m_wordWeights[word]; }
  std::uint32_t nodeWord(std::uint32_t node) const { return m_nodeWords[node]; }
  bool isLeaf(std::uint32_t node) const { return m_childBegin[node] == m_childBegin[node + 1]; }
  //! Depth of a node (root 0).
  int nodeDepth(std::uint32_t node) const { return m_depths[node]; }

  //! A copy of the tree as flat arrays (for writers).
  Parts parts() const;

  /*!
    Word of one descriptor, and optionally the node it passes at depth `indexDepth` (the leaf itself when the leaf
    is shallower). The vocabulary must not be empty.
  */
  std::uint32_t wordOf(const OrbDescriptor &d, int indexDepth = 0, std::uint32_t *indexNode = nullptr) const;

  //! BoW vector of an image's descriptors (see the class comment for the weighting). Empty input: empty vector.
  void transform(const std::vector<OrbDescriptor> &descriptors, BowVector &bow) const;

  /*!
    BoW vector and direct index. Features are grouped by the node they pass `levelsUp` levels above the deepest
    level L (depth max(0, L - levelsUp); ORB-SLAM2 uses 4 with L = 6).
  */
  void transform(const std::vector<OrbDescriptor> &descriptors, BowVector &bow, FeatureVector &direct,
                 int levelsUp) const;

  //! L1 score 1 - 0.5 |a - b|_1 of two L1-normalised vectors, in [0, 1] (DBoW2's L1Scoring).
  static double score(const BowVector &a, const BowVector &b);

  /*!
    A 64-bit fingerprint of the whole tree (structure, centroids, weights, weighting): two vocabularies with the
    same fingerprint give the same vectors. Map files store it to refuse a map built with another vocabulary.
  */
  std::uint64_t fingerprint() const { return m_fingerprint; }

private:
  //! The child of an inner node whose centroid is closest to \e d (Hamming).
  std::uint32_t closestChild(const OrbDescriptor &d, std::uint32_t node) const;
  void transformInto(const std::vector<OrbDescriptor> &descriptors, BowVector &bow, FeatureVector *direct,
                     int indexDepth) const;
  //! Children of every node in compressed rows (m_childBegin, m_children), their slots and descriptors.
  void buildChildTables(const Parts &parts, const std::vector<std::uint32_t> &childCount);

  int m_branching = 0;
  int m_levels = 0;
  VocabularyWeighting m_weighting = VocabularyWeighting::tfIdf;
  VocabularyScoring m_scoring = VocabularyScoring::l1;
  std::vector<std::uint32_t> m_parents;
  std::vector<std::uint32_t> m_childBegin; //!< children of node n: m_children[m_childBegin[n] .. m_childBegin[n+1])
  std::vector<std::uint32_t> m_children;
  //! Centroids in the order of m_children, so a descent reads each node's children from one contiguous block;
  //! slot 0 holds the root's (unused) descriptor and node n's centroid is m_childDescriptors[m_nodeSlots[n]].
  std::vector<OrbDescriptor> m_childDescriptors;
  std::vector<std::uint32_t> m_nodeSlots;
  std::vector<std::uint32_t> m_nodeWords; //!< word of each node, kNoWord for inner nodes
  std::vector<std::uint8_t> m_depths;
  std::vector<std::uint32_t> m_wordNodes;
  std::vector<double> m_wordWeights;
  std::uint64_t m_fingerprint = 0;
};

//! 64-bit hash of a byte range used by the vocabulary files and fingerprints (word-wise FNV-1a variant).
VISP_EXPORT std::uint64_t hashBytes(const void *data, std::size_t size, std::uint64_t seed = 0xcbf29ce484222325ull);
} // namespace hslam

#endif
