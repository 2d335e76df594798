/*
 * H-SLAM for ViSP.
 */
// Reading DBoW2's OpenCV-YAML vocabularies (plain or gzip) with a parser of their own layout.
#include "features/VocabularyFileSupport.h"
#include "features/VocabularyFiles.h"

#include "common/TextParsing.h"

#include <visp3/hslam/vpHSlamException.h>

#include <zlib.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

namespace hslam
{
namespace
{
//! Inflate a gzip stream; refuses corrupt streams and outputs over kMaxInflatedBytes (a "zip bomb").
std::string gunzip(const std::string &compressed, const std::string &path)
{
  constexpr std::size_t kMaxInflatedBytes = std::size_t(4) << 30;
  z_stream stream{};
  if (inflateInit2(&stream, 16 + MAX_WBITS) != Z_OK) {
    throwAt(vpHSlamException::fileUnreadable, path, 0, "cannot start gzip decompression");
  }
  stream.next_in = reinterpret_cast<Bytef *>(const_cast<char *>(compressed.data()));
  stream.avail_in = static_cast<uInt>(compressed.size());
  std::string out;
  char buffer[1 << 16];
  int status = Z_OK;
  while (status == Z_OK) {
    stream.next_out = reinterpret_cast<Bytef *>(buffer);
    stream.avail_out = sizeof(buffer);
    status = inflate(&stream, Z_NO_FLUSH);
    if (status != Z_OK && status != Z_STREAM_END) {
      break;
    }
    out.append(buffer, sizeof(buffer) - stream.avail_out);
    if (out.size() > kMaxInflatedBytes) {
      inflateEnd(&stream);
      throwAt(vpHSlamException::parseError, path, 0, "gzip content larger than 4 GiB");
    }
    if (status == Z_OK && stream.avail_in == 0 && stream.avail_out != 0) {
      break; // input exhausted before the end of the stream
    }
  }
  inflateEnd(&stream);
  if (status != Z_STREAM_END) {
    throwAt(vpHSlamException::parseError, path, 0, "corrupt or truncated gzip data");
  }
  return out;
}

} // namespace

namespace
{
//! Line (1-based) of a position in a text.
std::size_t lineAt(const std::string &text, std::size_t pos)
{
  return 1 + static_cast<std::size_t>(std::count(
                 text.begin(), text.begin() + static_cast<std::ptrdiff_t>(std::min(pos, text.size())), '\n'));
}

//! One flow map "{ key:value, key:"text", ... }" of DBoW2's YAML (no nesting), as key -> raw value.
std::vector<std::pair<std::string, std::string>> parseFlowMap(const std::string &body, const std::string &path,
                                                              std::size_t line)
{
  std::vector<std::pair<std::string, std::string>> fields;
  std::size_t i = 0;
  while (i < body.size()) {
    const std::size_t colon = body.find(':', i);
    if (colon == std::string::npos) {
      if (!trim(body.substr(i)).empty()) {
        throwAt(vpHSlamException::parseError, path, line, "expected 'key:value' in '{ ... }'");
      }
      break;
    }
    const std::string key = trim(body.substr(i, colon - i));
    std::size_t j = colon + 1;
    while (j < body.size() && (body[j] == ' ' || body[j] == '\t' || body[j] == '\n' || body[j] == '\r')) {
      ++j;
    }
    std::string value;
    if (j < body.size() && body[j] == '"') {
      const std::size_t close = body.find('"', j + 1);
      if (close == std::string::npos) {
        throwAt(vpHSlamException::parseError, path, line, "unterminated string in '{ ... }'");
      }
      value = body.substr(j + 1, close - j - 1);
      j = close + 1;
      const std::size_t comma = body.find(',', j);
      if (!trim(body.substr(j, comma == std::string::npos ? std::string::npos : comma - j)).empty()) {
        throwAt(vpHSlamException::parseError, path, line, "text after a string in '{ ... }'");
      }
      i = comma == std::string::npos ? body.size() : comma + 1;
    } else {
      const std::size_t comma = body.find(',', j);
      value = trim(body.substr(j, comma == std::string::npos ? std::string::npos : comma - j));
      i = comma == std::string::npos ? body.size() : comma + 1;
    }
    if (key.empty()) {
      throwAt(vpHSlamException::parseError, path, line, "empty key in '{ ... }'");
    }
    fields.emplace_back(key, value);
  }
  return fields;
}

const std::string *field(const std::vector<std::pair<std::string, std::string>> &fields, const std::string &key)
{
  for (const auto &f : fields) {
    if (f.first == key) {
      return &f.second;
    }
  }
  return nullptr;
}

//! The flow maps of a block sequence ("- { ... }" items) between two positions of the text.
std::vector<std::pair<std::size_t, std::string>> flowMaps(const std::string &text, std::size_t begin, std::size_t end,
                                                          const std::string &path)
{
  std::vector<std::pair<std::size_t, std::string>> maps;
  std::size_t i = begin;
  while (i < end) {
    const char ch = text[i];
    if (ch == '{') {
      const std::size_t close = text.find('}', i);
      if (close == std::string::npos || close > end) {
        throwAt(vpHSlamException::parseError, path, lineAt(text, i), "'{' without '}' (file cut short?)");
      }
      maps.emplace_back(lineAt(text, i), text.substr(i + 1, close - i - 1));
      i = close + 1;
    } else if (ch == '-' || ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r' || ch == '[' || ch == ']') {
      ++i;
    } else {
      throwAt(vpHSlamException::parseError, path, lineAt(text, i),
              std::string("unexpected character '") + ch + "' in a list of '{ ... }' entries");
    }
  }
  return maps;
}

int intField(const std::vector<std::pair<std::string, std::string>> &fields, const std::string &key,
             const std::string &path, std::size_t line)
{
  const std::string *value = field(fields, key);
  if (!value) {
    throwAt(vpHSlamException::parseError, path, line, "missing '" + key + "'");
  }
  long long parsed = 0;
  if (!tryParseInt64(*value, parsed) || parsed < 0 || parsed > 0x7fffffffLL) {
    throwAt(vpHSlamException::parseError, path, line, "'" + key + "': '" + *value + "' is not a non-negative integer");
  }
  return static_cast<int>(parsed);
}
} // namespace

namespace
{
using FlowMaps = std::vector<std::pair<std::size_t, std::string>>;

//! Offset of the first line at or after \e from that starts (trimmed) with "key:", npos when none.
std::size_t keyLine(const std::string &text, const std::string &key, std::size_t from)
{
  std::size_t pos = from;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) {
      end = text.size();
    }
    const std::string line = trim(text.substr(pos, end - pos));
    if (line.compare(0, key.size() + 1, key + ":") == 0) {
      return pos;
    }
    pos = end + 1;
  }
  return std::string::npos;
}

//! The integer scalar "key: value" of the vocabulary map (which starts at \e vocabularyAt).
int scalarField(const std::string &text, const std::string &key, std::size_t vocabularyAt, const std::string &path)
{
  const std::size_t at = keyLine(text, key, vocabularyAt);
  if (at == std::string::npos) {
    throwAt(vpHSlamException::parseError, path, 0, "missing or non-integer '" + key + "'");
  }
  const std::size_t end = text.find('\n', at);
  const std::string line = trim(text.substr(at, end == std::string::npos ? std::string::npos : end - at));
  std::vector<std::pair<std::string, std::string>> kv = {{key, trim(line.substr(key.size() + 1))}};
  return intField(kv, key, path, lineAt(text, at));
}

//! The "nodes" list: each node's parent and descriptor into \e parts, its weight into \e nodeWeights (ids 1..n-1).
void readNodes(const FlowMaps &nodeMaps, const std::string &path, OrbVocabulary::Parts &parts,
               std::vector<double> &nodeWeights)
{
  const std::size_t nodeCount = nodeMaps.size() + 1;
  parts.parents.assign(nodeCount, 0xffffffffu);
  parts.parents[0] = 0;
  parts.descriptors.assign(nodeCount, OrbDescriptor());
  nodeWeights.assign(nodeCount, 0.0);
  for (const auto &entry : nodeMaps) {
    const auto fields = parseFlowMap(entry.second, path, entry.first);
    const int id = intField(fields, "nodeId", path, entry.first);
    const int parent = intField(fields, "parentId", path, entry.first);
    if (id <= 0 || static_cast<std::size_t>(id) >= nodeCount ||
        parts.parents[static_cast<std::size_t>(id)] != 0xffffffffu) {
      throwAt(vpHSlamException::parseError, path, entry.first,
              "node id " + std::to_string(id) + " out of [1, " + std::to_string(nodeCount - 1) + "] or repeated");
    }
    const std::string *weight = field(fields, "weight");
    const std::string *descriptor = field(fields, "descriptor");
    if (!weight || !descriptor) {
      throwAt(vpHSlamException::parseError, path, entry.first, "node without weight or descriptor");
    }
    parts.parents[static_cast<std::size_t>(id)] = static_cast<std::uint32_t>(parent);
    nodeWeights[static_cast<std::size_t>(id)] = parseDouble(*weight, path, entry.first, "node weight");
    parts.descriptors[static_cast<std::size_t>(id)] =
        descriptorFromText(*descriptor, path, entry.first, "node " + std::to_string(id));
  }
}

//! The "words" list: each word's node into \e parts (word ids 0..n-1, each once; nodes among the \e nodeCount).
void readWords(const FlowMaps &wordMaps, std::size_t nodeCount, const std::string &path, OrbVocabulary::Parts &parts)
{
  parts.wordNodes.assign(wordMaps.size(), 0);
  std::vector<bool> seen(wordMaps.size(), false);
  for (const auto &entry : wordMaps) {
    const auto fields = parseFlowMap(entry.second, path, entry.first);
    const int word = intField(fields, "wordId", path, entry.first),
              node = intField(fields, "nodeId", path, entry.first);
    if (static_cast<std::size_t>(word) >= wordMaps.size() || seen[static_cast<std::size_t>(word)]) {
      throwAt(vpHSlamException::parseError, path, entry.first,
              "word id " + std::to_string(word) + " out of range or repeated");
    }
    if (node <= 0 || static_cast<std::size_t>(node) >= nodeCount) {
      throwAt(vpHSlamException::parseError, path, entry.first, "node id " + std::to_string(node) + " out of range");
    }
    seen[static_cast<std::size_t>(word)] = true;
    parts.wordNodes[static_cast<std::size_t>(word)] = static_cast<std::uint32_t>(node);
  }
}
} // namespace

OrbVocabulary loadVocabularyDbow2Yaml(const std::string &path)
{
  // DBoW2's YAML is read by a small parser of its own layout, not by OpenCV's YAML reader, which loops for ever on
  // some malformed files (found by fuzz_vocabulary_yaml). gzip is inflated here first.
  std::string text = readVocabularyFile(path);
  if (text.size() >= 2 && static_cast<unsigned char>(text[0]) == 0x1f && static_cast<unsigned char>(text[1]) == 0x8b) {
    text = gunzip(text, path);
  }
  requireNoNulByte(text, path);
  // Scalars and the two lists: "key:" at the start of a (trimmed) line.
  const std::size_t vocabularyAt = keyLine(text, "vocabulary", 0);
  if (vocabularyAt == std::string::npos) {
    throwAt(vpHSlamException::parseError, path, 0, "no 'vocabulary' map (not a DBoW2 YAML vocabulary)");
  }
  OrbVocabulary::Parts parts;
  parts.branching = scalarField(text, "k", vocabularyAt, path);
  parts.levels = scalarField(text, "L", vocabularyAt, path);
  const int scoring = scalarField(text, "scoringType", vocabularyAt, path),
            weighting = scalarField(text, "weightingType", vocabularyAt, path);
  if (scoring > kDbow2MaxScoring || weighting > kDbow2MaxWeighting) {
    throwAt(vpHSlamException::parseError, path, 0, "unknown scoring or weighting type");
  }
  parts.scoring = static_cast<VocabularyScoring>(scoring);
  parts.weighting = static_cast<VocabularyWeighting>(weighting);
  const std::size_t nodesAt = keyLine(text, "nodes", vocabularyAt), wordsAt = keyLine(text, "words", vocabularyAt);
  if (nodesAt == std::string::npos || wordsAt == std::string::npos || wordsAt < nodesAt) {
    throwAt(vpHSlamException::parseError, path, 0, "empty vocabulary (no 'nodes' or 'words' list)");
  }
  const std::size_t nodesBody = text.find(':', nodesAt) + 1, wordsBody = text.find(':', wordsAt) + 1;
  const FlowMaps nodeMaps = flowMaps(text, nodesBody, wordsAt, path);
  // After the words list, DBoW2 closes the vocabulary map: stop at the first line that is not part of the list.
  const FlowMaps wordMaps = flowMaps(text, wordsBody, text.size(), path);
  if (nodeMaps.empty() || wordMaps.empty()) {
    throwAt(vpHSlamException::parseError, path, 0, "empty vocabulary (no 'nodes' or 'words')");
  }
  std::vector<double> nodeWeights;
  readNodes(nodeMaps, path, parts, nodeWeights);
  readWords(wordMaps, nodeMaps.size() + 1, path, parts);
  parts.wordWeights.resize(parts.wordNodes.size());
  for (std::size_t w = 0; w < parts.wordNodes.size(); ++w) {
    parts.wordWeights[w] = nodeWeights[parts.wordNodes[w]];
  }
  OrbVocabulary vocabulary;
  vocabulary.assign(std::move(parts), path);
  return vocabulary;
}

} // namespace hslam
