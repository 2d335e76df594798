/*
 * H-SLAM for ViSP.
 */
#include "features/OrbVocabulary.h"

#include "common/BinaryIo.h"
#include "common/TextParsing.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>

namespace hslam
{
namespace
{
//! What the descent of transformInto() reads of the tree.
struct DescentTables {
  const std::uint32_t *childBegin; //!< OrbVocabulary::m_childBegin
  const std::uint32_t *children;   //!< OrbVocabulary::m_children
  const OrbDescriptor *centroids;  //!< the children's centroids, in the order of children
  int levels;
};

/*!
  Child of \e node (not a leaf) whose centroid is closest to \e d; ties keep the first child, as DBoW2. kBuiltin:
  distances by hammingDistanceBuiltin() (only where inlined into descendWithPopcnt()), else by hammingDistance().
*/
template <bool kBuiltin>
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline std::uint32_t
closestChildIn(const DescentTables &t, const OrbDescriptor &d, std::uint32_t node)
{
  const std::uint32_t begin = t.childBegin[node], end = t.childBegin[node + 1];
  std::uint32_t best = begin;
  int bestDistance = kBuiltin ? hammingDistanceBuiltin(d, t.centroids[begin]) : hammingDistance(d, t.centroids[begin]);
  for (std::uint32_t c = begin + 1; c < end; ++c) {
    const int distance = kBuiltin ? hammingDistanceBuiltin(d, t.centroids[c]) : hammingDistance(d, t.centroids[c]);
    if (distance < bestDistance) {
      bestDistance = distance;
      best = c;
    }
  }
  return t.children[best];
}

/*!
  Descends all descriptors together, one level at a time, prefetching the children block of the descriptor a few
  places ahead: below the first levels every block is a cache miss, and interleaving hides most of the latency
  (about 2x faster than one descriptor at a time on 2000 descriptors). \e current ends at each descriptor's leaf,
  \e indexNodes (optional) at its node of depth \e indexDepth. kBuiltin: as closestChildIn().
*/
template <bool kBuiltin>
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline void
descend(const DescentTables &t, const std::vector<OrbDescriptor> &descriptors, std::vector<std::uint32_t> &current,
        std::vector<std::uint32_t> *indexNodes, int indexDepth)
{
  const std::size_t n = descriptors.size();
  constexpr std::size_t kPrefetchDistance = 8;
  for (int depth = 1; depth <= t.levels; ++depth) {
    bool descended = false;
    for (std::size_t i = 0; i < n; ++i) {
      if (i + kPrefetchDistance < n) {
        const std::uint32_t ahead = current[i + kPrefetchDistance];
        const char *block = reinterpret_cast<const char *>(t.centroids + t.childBegin[ahead]);
        const std::size_t bytes = (t.childBegin[ahead + 1] - t.childBegin[ahead]) * sizeof(OrbDescriptor);
        for (std::size_t offset = 0; offset < bytes; offset += 64) {
          __builtin_prefetch(block + offset);
        }
      }
      if (t.childBegin[current[i]] == t.childBegin[current[i] + 1]) {
        continue; // reached a leaf already
      }
      current[i] = closestChildIn<kBuiltin>(t, descriptors[i], current[i]);
      if (indexNodes && depth <= indexDepth) {
        (*indexNodes)[i] = current[i];
      }
      descended = true;
    }
    if (!descended) {
      break;
    }
  }
}

HSLAM_TARGET_POPCNT void descendWithPopcnt(const DescentTables &t, const std::vector<OrbDescriptor> &descriptors,
                                           std::vector<std::uint32_t> &current, std::vector<std::uint32_t> *indexNodes,
                                           int indexDepth)
{
  descend<HSLAM_POPCNT_DISPATCH != 0>(t, descriptors, current, indexNodes, indexDepth);
}

void descendPortable(const DescentTables &t, const std::vector<OrbDescriptor> &descriptors,
                     std::vector<std::uint32_t> &current, std::vector<std::uint32_t> *indexNodes, int indexDepth)
{
  descend<false>(t, descriptors, current, indexNodes, indexDepth);
}

constexpr std::uint64_t kHashPrime = 0x100000001b3ull;

[[noreturn]] void badTree(const std::string &origin, const std::string &what)
{
  throwAt(vpHSlamException::parseError, origin, 0, "not a valid vocabulary tree: " + what);
}
} // namespace

std::uint64_t hashBytes(const void *data, std::size_t size, std::uint64_t seed)
{
  // FNV-1a over little-endian 64-bit words (the tail padded with zeros), then a final avalanche (splitmix64):
  // eight times fewer multiplications than byte-wise FNV, so a 50 MB vocabulary hashes in a few milliseconds.
  const auto *bytes = static_cast<const std::uint8_t *>(data);
  std::uint64_t h = seed ^ static_cast<std::uint64_t>(size);
  std::size_t i = 0;
  for (; i + 8 <= size; i += 8) {
    h = (h ^ loadU64(bytes + i)) * kHashPrime;
  }
  if (i < size) {
    std::uint64_t word = 0;
    for (int b = 0; i + b < size; ++b) {
      word |= static_cast<std::uint64_t>(bytes[i + b]) << (8 * b);
    }
    h = (h ^ word) * kHashPrime;
  }
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebull;
  h ^= h >> 31;
  return h;
}

namespace
{
//! The tree's parameters are within bounds and its parts' sizes agree.
void checkSizes(const OrbVocabulary::Parts &parts, const std::string &origin)
{
  const std::size_t nodes = parts.parents.size();
  if (parts.branching < 2 || parts.branching > OrbVocabulary::kMaxBranching) {
    badTree(origin, "branching factor k = " + std::to_string(parts.branching) + " outside [2, " +
                        std::to_string(OrbVocabulary::kMaxBranching) + "]");
  }
  if (parts.levels < 1 || parts.levels > OrbVocabulary::kMaxLevels) {
    badTree(origin, "depth L = " + std::to_string(parts.levels) + " outside [1, " +
                        std::to_string(OrbVocabulary::kMaxLevels) + "]");
  }
  if (nodes < 2 || parts.wordNodes.empty()) {
    badTree(origin, "empty (no word)");
  }
  if (parts.descriptors.size() != nodes || parts.wordWeights.size() != parts.wordNodes.size()) {
    badTree(origin, "inconsistent node or word counts");
  }
  if (nodes >= OrbVocabulary::kNoWord || parts.wordNodes.size() >= OrbVocabulary::kNoWord) {
    badTree(origin, "too many nodes");
  }
}

//! Every parent precedes its child, no node lies deeper than L and none has more than k children; each node's
//! depth and number of children.
void checkTree(const OrbVocabulary::Parts &parts, const std::string &origin, std::vector<std::uint8_t> &depths,
               std::vector<std::uint32_t> &childCount)
{
  const std::size_t nodes = parts.parents.size();
  depths.assign(nodes, 0);
  childCount.assign(nodes, 0);
  for (std::size_t n = 1; n < nodes; ++n) {
    const std::uint32_t p = parts.parents[n];
    if (p >= n) {
      badTree(origin, "node " + std::to_string(n) + " has parent " + std::to_string(p) + ", which does not precede it");
    }
    if (depths[p] >= parts.levels) {
      badTree(origin, "node " + std::to_string(n) + " lies deeper than L = " + std::to_string(parts.levels));
    }
    depths[n] = static_cast<std::uint8_t>(depths[p] + 1);
    if (++childCount[p] > static_cast<std::uint32_t>(parts.branching)) {
      badTree(origin,
              "node " + std::to_string(p) + " has more than k = " + std::to_string(parts.branching) + " children");
    }
  }
}

//! Each word is its own leaf with a finite, non-negative weight, and every leaf is a word: each node's word
//! (kNoWord for inner nodes).
std::vector<std::uint32_t> nodeWordsOf(const OrbVocabulary::Parts &parts, const std::vector<std::uint32_t> &childCount,
                                       const std::string &origin)
{
  const std::size_t nodes = parts.parents.size();
  std::vector<std::uint32_t> nodeWords(nodes, OrbVocabulary::kNoWord);
  for (std::size_t w = 0; w < parts.wordNodes.size(); ++w) {
    const std::uint32_t n = parts.wordNodes[w];
    if (n == 0 || n >= nodes) {
      badTree(origin, "word " + std::to_string(w) + " refers to node " + std::to_string(n) + ", not a leaf");
    }
    if (nodeWords[n] != OrbVocabulary::kNoWord) {
      badTree(origin, "node " + std::to_string(n) + " is both word " + std::to_string(nodeWords[n]) + " and word " +
                          std::to_string(w));
    }
    if (!std::isfinite(parts.wordWeights[w]) || parts.wordWeights[w] < 0.0) {
      badTree(origin, "word " + std::to_string(w) + " has weight " + std::to_string(parts.wordWeights[w]));
    }
    nodeWords[n] = static_cast<std::uint32_t>(w);
  }
  for (std::size_t n = 1; n < nodes; ++n) {
    if ((childCount[n] == 0) != (nodeWords[n] != OrbVocabulary::kNoWord)) {
      badTree(origin, "node " + std::to_string(n) +
                          (childCount[n] == 0 ? " is a leaf without a word" : " has children and is also a word"));
    }
  }
  if (childCount[0] == 0) {
    badTree(origin, "the root has no children");
  }
  return nodeWords;
}
} // namespace

void OrbVocabulary::buildChildTables(const Parts &parts, const std::vector<std::uint32_t> &childCount)
{
  const std::size_t nodes = parts.parents.size();
  m_childBegin.assign(nodes + 1, 0);
  for (std::size_t n = 0; n < nodes; ++n) {
    m_childBegin[n + 1] = m_childBegin[n] + childCount[n];
  }
  // Slot 0 is the root; children of node n occupy slots 1 + [m_childBegin[n], m_childBegin[n+1]).
  m_children.assign(nodes - 1, 0);
  m_childDescriptors.assign(nodes, OrbDescriptor());
  m_nodeSlots.assign(nodes, 0);
  std::vector<std::uint32_t> fill(m_childBegin.begin(), m_childBegin.end() - 1);
  for (std::size_t n = 1; n < nodes; ++n) {
    const std::uint32_t position = fill[parts.parents[n]]++;
    m_children[position] = static_cast<std::uint32_t>(n);
    m_nodeSlots[n] = position + 1;
    m_childDescriptors[position + 1] = parts.descriptors[n];
  }
}

void OrbVocabulary::assign(Parts parts, const std::string &origin)
{
  checkSizes(parts, origin);
  std::vector<std::uint8_t> depths;
  std::vector<std::uint32_t> childCount;
  checkTree(parts, origin, depths, childCount);
  std::vector<std::uint32_t> nodeWords = nodeWordsOf(parts, childCount, origin);
  // Children in compressed rows, in node order (so descent ties go to the first child, as DBoW2).
  buildChildTables(parts, childCount);

  m_branching = parts.branching;
  m_levels = parts.levels;
  m_weighting = parts.weighting;
  m_scoring = parts.scoring;
  parts.parents[0] = 0;
  parts.descriptors[0] = OrbDescriptor();
  m_parents = std::move(parts.parents);
  m_nodeWords = std::move(nodeWords);
  m_depths = std::move(depths);
  m_wordNodes = std::move(parts.wordNodes);
  m_wordWeights = std::move(parts.wordWeights);

  std::uint64_t h = hashBytes(m_parents.data(), m_parents.size() * sizeof(std::uint32_t));
  h = hashBytes(parts.descriptors.data(), parts.descriptors.size() * sizeof(OrbDescriptor), h);
  h = hashBytes(m_wordNodes.data(), m_wordNodes.size() * sizeof(std::uint32_t), h);
  h = hashBytes(m_wordWeights.data(), m_wordWeights.size() * sizeof(double), h);
  const int header[3] = {m_branching, m_levels, static_cast<int>(m_weighting)};
  m_fingerprint = hashBytes(header, sizeof(header), h);
}

OrbVocabulary::Parts OrbVocabulary::parts() const
{
  Parts p;
  p.branching = m_branching;
  p.levels = m_levels;
  p.weighting = m_weighting;
  p.scoring = m_scoring;
  p.parents = m_parents;
  p.descriptors.resize(m_parents.size());
  for (std::size_t n = 1; n < m_parents.size(); ++n) {
    p.descriptors[n] = m_childDescriptors[m_nodeSlots[n]];
  }
  p.wordNodes = m_wordNodes;
  p.wordWeights = m_wordWeights;
  return p;
}

std::uint32_t OrbVocabulary::closestChild(const OrbDescriptor &d, std::uint32_t node) const
{
  const DescentTables tables{m_childBegin.data(), m_children.data(), m_childDescriptors.data() + 1, m_levels};
  return closestChildIn<false>(tables, d, node);
}

std::uint32_t OrbVocabulary::wordOf(const OrbDescriptor &d, int indexDepth, std::uint32_t *indexNode) const
{
  std::uint32_t node = 0;
  int depth = 0;
  if (indexNode) {
    *indexNode = 0;
  }
  while (m_childBegin[node] != m_childBegin[node + 1]) {
    node = closestChild(d, node);
    ++depth;
    if (indexNode && depth <= indexDepth) {
      *indexNode = node;
    }
  }
  return m_nodeWords[node];
}

void OrbVocabulary::transform(const std::vector<OrbDescriptor> &descriptors, BowVector &bow) const
{
  transformInto(descriptors, bow, nullptr, 0);
}

void OrbVocabulary::transform(const std::vector<OrbDescriptor> &descriptors, BowVector &bow, FeatureVector &direct,
                              int levelsUp) const
{
  transformInto(descriptors, bow, &direct, std::max(0, m_levels - levelsUp));
}

void OrbVocabulary::transformInto(const std::vector<OrbDescriptor> &descriptors, BowVector &bow, FeatureVector *direct,
                                  int indexDepth) const
{
  bow.clear();
  if (direct) {
    direct->clear();
  }
  if (empty() || descriptors.empty()) {
    return;
  }
  const std::size_t n = descriptors.size();
  std::vector<std::uint32_t> current(n, 0), indexNodes(direct ? n : 0, 0);
  const DescentTables tables{m_childBegin.data(), m_children.data(), m_childDescriptors.data() + 1, m_levels};
  if (cpuHasPopcnt()) {
    descendWithPopcnt(tables, descriptors, current, direct ? &indexNodes : nullptr, indexDepth);
  } else {
    descendPortable(tables, descriptors, current, direct ? &indexNodes : nullptr, indexDepth);
  }
  // (word, feature) and (node, feature) pairs, sorted afterwards: one allocation each, no map.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> words, nodes;
  words.reserve(n);
  if (direct) {
    nodes.reserve(n);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t word = m_nodeWords[current[i]];
    if (m_wordWeights[word] > 0.0) {
      words.emplace_back(word, static_cast<std::uint32_t>(i));
      if (direct) {
        nodes.emplace_back(indexNodes[i], static_cast<std::uint32_t>(i));
      }
    }
  }
  std::sort(words.begin(), words.end());
  const bool accumulate = m_weighting == VocabularyWeighting::tfIdf || m_weighting == VocabularyWeighting::tf;
  double total = 0.0;
  for (std::size_t i = 0; i < words.size();) {
    std::size_t j = i + 1;
    while (j < words.size() && words[j].first == words[i].first) {
      ++j;
    }
    const double weight = m_wordWeights[words[i].first] * (accumulate ? static_cast<double>(j - i) : 1.0);
    bow.push_back({words[i].first, weight});
    total += weight;
    i = j;
  }
  // TF divides by the feature count and L1 normalisation by the total: only the latter matters for the result.
  if (total > 0.0) {
    for (BowEntry &e : bow) {
      e.weight /= total;
    }
  }
  if (direct) {
    std::sort(nodes.begin(), nodes.end());
    for (const auto &nf : nodes) {
      if (direct->empty() || direct->back().nodeId != nf.first) {
        direct->push_back({nf.first, {}});
      }
      direct->back().features.push_back(nf.second);
    }
  }
}

double OrbVocabulary::score(const BowVector &a, const BowVector &b)
{
  // DBoW2 L1Scoring: sum over common words of |a_i - b_i| - |a_i| - |b_i|, i.e. -|a - b|_1 + |a|_1 + |b|_1 - 2 once
  // the words that are not common are accounted for; with unit-L1 vectors this is 1 - 0.5 |a - b|_1.
  double sum = 0.0;
  auto ia = a.begin(), ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (ia->wordId < ib->wordId) {
      ++ia;
    } else if (ib->wordId < ia->wordId) {
      ++ib;
    } else {
      sum += std::fabs(ia->weight - ib->weight) - std::fabs(ia->weight) - std::fabs(ib->weight);
      ++ia;
      ++ib;
    }
  }
  return -0.5 * sum;
}
} // namespace hslam
