/*
 * H-SLAM for ViSP.
 */
#include "loop/KeyframeDatabase.h"

#include "common/HeapBytes.h"
#include "features/OrbVocabulary.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <functional>
#include <mutex>
#include <string>

namespace hslam
{
KeyframeDatabase::KeyframeDatabase(std::size_t wordCount, const KeyframeDatabaseOptions &options)
    : m_options(options), m_wordCount(wordCount)
{
  if (!(options.minCommonWordsRatio >= 0.0 && options.minCommonWordsRatio <= 1.0) ||
      !(options.groupRetainRatio >= 0.0 && options.groupRetainRatio <= 1.0) || options.groupNeighbours < 0) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "keyframe database: ratios must lie in [0, 1] and the neighbour count be >= 0");
  }
}

void KeyframeDatabase::add(KeyframeId id, const BowVector &bow)
{
  std::unique_lock<std::shared_mutex> lock(m_mutex);
  if (m_vectors.count(id)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "keyframe database: keyframe " + std::to_string(id) + " is already present");
  }
  for (const BowEntry &e : bow) {
    if (e.wordId >= m_wordCount) {
      throw vpHSlamException(vpHSlamException::invalidArgument,
                             "keyframe database: word " + std::to_string(e.wordId) + " of keyframe " +
                                 std::to_string(id) + " is outside the vocabulary (" + std::to_string(m_wordCount) +
                                 " words): built with another vocabulary?");
    }
  }
  using Index = decltype(m_index);
  using Vectors = decltype(m_vectors);
  for (const BowEntry &e : bow) {
    std::uint32_t slot = m_freeHolders;
    if (slot != kNoHolder) {
      m_freeHolders = m_holders[slot].next;
    } else {
      slot = static_cast<std::uint32_t>(m_holders.size());
      m_holders.push_back(Holder());
    }
    const auto inserted = m_index.try_emplace(e.wordId, kNoHolder);
    m_holders[slot] = {id, inserted.first->second}; // in front of the word's chain
    inserted.first->second = slot;
    m_heapBytes += inserted.second ? hashNodeHeapBytes<Index>() : 0.;
  }
  const auto stored = m_vectors.emplace(id, bow).first;
  m_heapBytes += hashNodeHeapBytes<Vectors>() + vectorHeapBytes(stored->second);
}

bool KeyframeDatabase::remove(KeyframeId id)
{
  std::unique_lock<std::shared_mutex> lock(m_mutex);
  const auto it = m_vectors.find(id);
  if (it == m_vectors.end()) {
    return false;
  }
  for (const BowEntry &e : it->second) {
    const auto word = m_index.find(e.wordId);
    if (word == m_index.end()) {
      continue;
    }
    // Unlink the keyframe's entry from the word's chain; it joins the free chain.
    std::uint32_t *link = &word->second;
    while (*link != kNoHolder && m_holders[*link].id != id) {
      link = &m_holders[*link].next;
    }
    if (*link != kNoHolder) {
      const std::uint32_t slot = *link;
      *link = m_holders[slot].next;
      m_holders[slot].next = m_freeHolders;
      m_freeHolders = slot;
    }
    if (word->second == kNoHolder) {
      m_heapBytes -= hashNodeHeapBytes<decltype(m_index)>();
      m_index.erase(word);
    }
  }
  m_heapBytes -= hashNodeHeapBytes<decltype(m_vectors)>() + vectorHeapBytes(it->second);
  m_vectors.erase(it);
  return true;
}

void KeyframeDatabase::clear()
{
  std::unique_lock<std::shared_mutex> lock(m_mutex);
  m_index.clear();
  std::vector<Holder>().swap(m_holders); // clear() would keep the capacity
  m_freeHolders = kNoHolder;
  m_vectors.clear();
  m_heapBytes = 0.;
}

std::size_t KeyframeDatabase::size() const
{
  std::shared_lock<std::shared_mutex> lock(m_mutex);
  return m_vectors.size();
}

bool KeyframeDatabase::contains(KeyframeId id) const
{
  std::shared_lock<std::shared_mutex> lock(m_mutex);
  return m_vectors.count(id) > 0;
}

bool KeyframeDatabase::vectorOf(KeyframeId id, BowVector &bow) const
{
  std::shared_lock<std::shared_mutex> lock(m_mutex);
  const auto it = m_vectors.find(id);
  if (it == m_vectors.end()) {
    return false;
  }
  bow = it->second;
  return true;
}

std::vector<double> KeyframeDatabase::scoresWith(const BowVector &bow, const std::vector<KeyframeId> &ids) const
{
  std::shared_lock<std::shared_mutex> lock(m_mutex);
  std::vector<double> scores;
  for (KeyframeId id : ids) {
    const auto it = m_vectors.find(id);
    if (it != m_vectors.end()) {
      scores.push_back(OrbVocabulary::score(bow, it->second));
    }
  }
  return scores;
}

std::unordered_map<KeyframeDatabase::KeyframeId, int> KeyframeDatabase::sharedWordCounts(const BowVector &bow) const
{
  std::unordered_map<KeyframeId, int> common;
  for (const BowEntry &e : bow) {
    const auto word = m_index.find(e.wordId); // absent: no keyframe holds it (or another vocabulary's word)
    if (word == m_index.end()) {
      continue;
    }
    for (std::uint32_t h = word->second; h != kNoHolder; h = m_holders[h].next) {
      ++common[m_holders[h].id];
    }
  }
  return common;
}

namespace
{
using Candidate = KeyframeDatabase::Candidate;
using KeyframeId = KeyframeDatabase::KeyframeId;

/*!
  The largest count of shared words among the keyframes of \e common the query does not exclude (0: none). Asked in
  decreasing count, so the exclusion rule runs on the few best keyframes, not on every keyframe sharing a word (a map
  revisited lap after lap has thousands of those: the rule on each was a quarter of the query's time).
*/
int largestCommonNotExcluded(const std::unordered_map<KeyframeId, int> &common, const KeyframeDatabase::Query &query)
{
  std::vector<std::pair<int, KeyframeId>> byCount;
  byCount.reserve(common.size());
  for (const auto &kc : common) {
    byCount.emplace_back(kc.second, kc.first);
  }
  std::sort(byCount.begin(), byCount.end(), std::greater<std::pair<int, KeyframeId>>());
  for (const auto &entry : byCount) {
    if (!query.excluded || !query.excluded(entry.second)) {
      return entry.first;
    }
  }
  return 0;
}

//! Groups by co-visibility: the group of a candidate is itself and its best \e groupNeighbours neighbours that are
//! candidates, represented by its best-scoring member and scored by the sum.
std::vector<Candidate> groupByCovisibility(const std::unordered_map<KeyframeId, Candidate> &scored,
                                           const KeyframeDatabase::Query &query, int groupNeighbours)
{
  std::vector<Candidate> groups;
  groups.reserve(scored.size());
  for (const auto &entry : scored) {
    Candidate best = entry.second;
    double groupScore = entry.second.score;
    if (query.covisible) {
      const std::vector<KeyframeId> neighbours = query.covisible(entry.first);
      const std::size_t count = std::min(neighbours.size(), static_cast<std::size_t>(groupNeighbours));
      for (std::size_t i = 0; i < count; ++i) {
        const auto it = scored.find(neighbours[i]);
        if (it == scored.end() || it->first == entry.first) {
          continue;
        }
        groupScore += it->second.score;
        if (it->second.score > best.score || (it->second.score == best.score && it->first < best.id)) {
          best = it->second;
        }
      }
    }
    best.groupScore = groupScore;
    groups.push_back(best);
  }
  return groups;
}

//! The groups within \e retainRatio of the best one, one entry per representative keyframe, best first.
std::vector<Candidate> retainBestGroups(std::vector<Candidate> &groups, const KeyframeDatabase::Query &query,
                                        double retainRatio)
{
  double bestGroup = 0.0;
  for (const Candidate &g : groups) {
    bestGroup = std::max(bestGroup, g.groupScore);
  }
  const double retain = retainRatio * bestGroup;
  std::sort(groups.begin(), groups.end(), [](const Candidate &a, const Candidate &b) {
    if (a.groupScore != b.groupScore) {
      return a.groupScore > b.groupScore;
    }
    if (a.score != b.score) {
      return a.score > b.score;
    }
    return a.id < b.id;
  });
  std::vector<Candidate> result;
  for (const Candidate &g : groups) {
    if (g.groupScore < retain) {
      break;
    }
    const bool seen = std::any_of(result.begin(), result.end(), [&](const Candidate &r) { return r.id == g.id; });
    if (!seen) {
      result.push_back(g);
      if (query.maxCandidates > 0 && result.size() >= query.maxCandidates) {
        break;
      }
    }
  }
  return result;
}
} // namespace

std::vector<KeyframeDatabase::Candidate> KeyframeDatabase::query(const BowVector &bow, const Query &query) const
{
  std::shared_lock<std::shared_mutex> lock(m_mutex);
  // 1. Keyframes sharing words, with the count of shared words.
  const std::unordered_map<KeyframeId, int> common = sharedWordCounts(bow);
  const int maxCommon = largestCommonNotExcluded(common, query);
  if (maxCommon == 0) {
    return {};
  }

  // 2. Score the keyframes sharing enough words.
  const double minCommon = m_options.minCommonWordsRatio * maxCommon;
  std::unordered_map<KeyframeId, Candidate> scored;
  for (const auto &kc : common) {
    if (kc.second < minCommon || (query.excluded && query.excluded(kc.first))) {
      continue;
    }
    Candidate c;
    c.id = kc.first;
    c.commonWords = kc.second;
    c.score = OrbVocabulary::score(bow, m_vectors.at(kc.first));
    c.normalizedScore = query.expectedScore > 0.0 ? c.score / query.expectedScore : c.score;
    c.groupScore = c.score;
    if (c.score >= query.minScore && c.normalizedScore >= query.minNormalizedScore) {
      scored.emplace(c.id, c);
    }
  }

  // 3. Group by co-visibility; 4. keep the groups close to the best one.
  std::vector<Candidate> groups = groupByCovisibility(scored, query, m_options.groupNeighbours);
  return retainBestGroups(groups, query, m_options.groupRetainRatio);
}

double KeyframeDatabase::memoryBytes() const
{
  std::shared_lock<std::shared_mutex> lock(m_mutex);
  return m_heapBytes + vectorHeapBytes(m_holders) + hashBucketsHeapBytes(m_index) + hashBucketsHeapBytes(m_vectors);
}
} // namespace hslam
