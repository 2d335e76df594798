/*
 * H-SLAM for ViSP.
 */
#include "map/MapFile.h"

#include "common/BinaryIo.h"
#include "common/TextParsing.h"
#include "features/OrbVocabulary.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <set>

namespace hslam
{
namespace
{
const char kMagic[8] = {'H', 'S', 'L', 'A', 'M', 'M', 'A', 'P'};
constexpr std::size_t kChecksumBytes = 8;
//! Fixed part of a keyframe record, of a point record (without observers) and of an edge record, in bytes.
constexpr std::size_t kKeyframeRecordBytes = 3 * 4 + 2 * 8 + 7 * 8 + 2 * 8 + 1 + 4;
constexpr std::size_t kPointRecordBytes = 4 * 4 + kOrbDescriptorBytes + 4 + 1 + 1 + 4;
constexpr std::size_t kEdgeRecordBytes = 2 * 4 + 7 * 8 + 36 * 8 + 1;
constexpr std::uint8_t kFlagCorner = 1;
constexpr std::uint8_t kFlagHasOrb = 2;
//! A stored quaternion must be unit to this tolerance on its squared norm (it was written normalised).
constexpr double kUnitQuaternionTolerance = 1e-6;
//! Keyframe ids and segments above this are refused: the system numbers its next ones after them.
constexpr int kMaxId = 1 << 30;
//! Within this, the stored quaternion is the unit one that was written (a few ulps of the squared norm).
constexpr double kExactUnitTolerance = 1e-14;

void writePose(ByteWriter &w, const SE3d &T)
{
  const Eigen::Quaterniond &q = T.unitQuaternion();
  w.f64(q.x());
  w.f64(q.y());
  w.f64(q.z());
  w.f64(q.w());
  w.f64(T.translation().x());
  w.f64(T.translation().y());
  w.f64(T.translation().z());
}

[[noreturn]] void corrupt(const std::string &path, const std::string &why)
{
  throwAt(vpHSlamException::parseError, path, 0, "corrupt map file: " + why);
}

SE3d readPose(ByteReader &r, const std::string &path, const char *what)
{
  double v[7];
  for (double &x : v) {
    x = r.f64(what);
    if (!std::isfinite(x)) {
      corrupt(path, std::string("non-finite value in ") + what);
    }
  }
  const Eigen::Quaterniond q(v[3], v[0], v[1], v[2]);
  if (std::fabs(q.squaredNorm() - 1.) > kUnitQuaternionTolerance) {
    corrupt(path, std::string(what) + " rotation is not a unit quaternion");
  }
  // Written unit by this format: kept as read (exact round trip); a quaternion a little off is normalised.
  const Eigen::Vector3d t(v[4], v[5], v[6]);
  return std::fabs(q.squaredNorm() - 1.) <= kExactUnitTolerance ? SE3d::fromUnitQuaternion(q, t) : SE3d(q, t);
}

double finite(double x, const std::string &path, const char *what)
{
  if (!std::isfinite(x)) {
    corrupt(path, std::string("non-finite ") + what);
  }
  return x;
}

void readPoint(ByteReader &r, const MapCamera &camera, std::uint32_t version, const std::string &path, GlobalPoint &p)
{
  p.u = static_cast<float>(finite(r.f32("a point's pixel"), path, "point pixel"));
  p.v = static_cast<float>(finite(r.f32("a point's pixel"), path, "point pixel"));
  if (p.u < 0.f || p.v < 0.f || p.u > static_cast<float>(camera.width - 1) ||
      p.v > static_cast<float>(camera.height - 1)) {
    corrupt(path, "point pixel outside the image");
  }
  p.idepth = static_cast<float>(finite(r.f32("a point's inverse depth"), path, "inverse depth"));
  p.idepthVar = static_cast<float>(finite(r.f32("a point's variance"), path, "inverse depth variance"));
  if (!(p.idepth > 0.f) || p.idepthVar < 0.f) {
    corrupt(path, "point with a non-positive inverse depth or a negative variance");
  }
  std::uint8_t orb[kOrbDescriptorBytes];
  r.raw(orb, sizeof(orb), "a point's descriptor");
  p.orb = descriptorFromBytes(orb);
  p.orbAngleDeg = static_cast<float>(finite(r.f32("a point's descriptor angle"), path, "descriptor angle"));
  const std::uint8_t flags = r.u8("a point's flags");
  if (flags & ~(kFlagCorner | kFlagHasOrb)) {
    corrupt(path, "unknown point flags");
  }
  p.isCorner = (flags & kFlagCorner) != 0;
  p.hasOrb = (flags & kFlagHasOrb) != 0;
  const std::uint8_t state = r.u8("a point's state");
  if (state > static_cast<std::uint8_t>(GlobalPointState::fused)) {
    corrupt(path, "unknown point state " + std::to_string(state));
  }
  p.state = static_cast<GlobalPointState>(state);
  const std::uint32_t observers = r.u32("a point's observer count");
  // Version 1 stored observer ids only; version 2 adds the pixel each observer saw the point at (NaN: unknown).
  r.requireRecords(observers, version == 1 ? 4 : 12, "observers");
  p.observers.resize(observers);
  const float unknown = std::numeric_limits<float>::quiet_NaN();
  p.observedAt.assign(observers, {unknown, unknown});
  for (size_t i = 0; i < observers; ++i) {
    p.observers[i] = r.i32("an observer id");
    if (version == 1) {
      continue;
    }
    for (float &x : p.observedAt[i]) {
      x = r.f32("an observer's pixel");
      if (std::isinf(x)) {
        corrupt(path, "infinite observer pixel");
      }
    }
  }
}
} // namespace

void saveMapFile(const std::string &path, const MapSnapshot &map)
{
  ByteWriter w;
  w.raw(kMagic, sizeof(kMagic));
  w.u32(kMapFileVersion);
  w.u32(static_cast<std::uint32_t>(kOrbDescriptorBytes));
  w.i32(map.camera.width);
  w.i32(map.camera.height);
  w.f64(map.camera.fx);
  w.f64(map.camera.fy);
  w.f64(map.camera.cx);
  w.f64(map.camera.cy);
  w.u64(map.vocabularyId);
  w.u32(static_cast<std::uint32_t>(map.keyframes.size()));
  for (const GlobalKeyframe &kf : map.keyframes) {
    w.i32(kf.id);
    w.i32(kf.frameId);
    w.i32(kf.segment);
    w.f64(kf.timestamp);
    w.f64(kf.exposure);
    writePose(w, kf.cMw);
    w.f64(kf.affine.a);
    w.f64(kf.affine.b);
    w.u8(kf.culled ? 1 : 0);
    w.u32(static_cast<std::uint32_t>(kf.points.size()));
    for (const GlobalPoint &p : kf.points) {
      w.f32(p.u);
      w.f32(p.v);
      w.f32(p.idepth);
      w.f32(p.idepthVar);
      for (int j = 0; j < kOrbDescriptorBytes; ++j) {
        w.u8(p.orb.byte(j));
      }
      w.f32(p.orbAngleDeg);
      w.u8(static_cast<std::uint8_t>((p.isCorner ? kFlagCorner : 0) | (p.hasOrb ? kFlagHasOrb : 0)));
      w.u8(static_cast<std::uint8_t>(p.state));
      w.u32(static_cast<std::uint32_t>(p.observers.size()));
      for (size_t i = 0; i < p.observers.size(); ++i) {
        w.i32(p.observers[i]);
        const float unknown = std::numeric_limits<float>::quiet_NaN();
        w.f32(i < p.observedAt.size() ? p.observedAt[i][0] : unknown);
        w.f32(i < p.observedAt.size() ? p.observedAt[i][1] : unknown);
      }
    }
  }
  w.u32(static_cast<std::uint32_t>(map.edges.size()));
  for (const PosePoseEdge &e : map.edges) {
    w.i32(e.from);
    w.i32(e.to);
    writePose(w, e.toMfrom);
    for (int i = 0; i < 6; ++i) {
      for (int j = 0; j < 6; ++j) {
        w.f64(e.information(i, j));
      }
    }
    w.u8(e.consecutive ? 1 : 0);
  }
  w.u8(map.metric.present ? 1 : 0);
  if (map.metric.present) {
    w.u8(map.metric.tagFrame ? 1 : 0);
    w.i32(map.metric.segment);
    writePose(w, map.metric.oMw);
    w.f64(map.metric.scale);
    w.f64(map.metric.scaleUncertainty);
  }
  w.u64(hashBytes(w.bytes().data(), w.bytes().size()));
  writeFileAtomically(path, w.bytes(), "map file");
}

MapSnapshot loadMapFile(const std::string &path)
{
  return parseMapFile(readBinaryFile(path, "map file"), path);
}

namespace
{
//! Checks the magic, the format version, the descriptor size and the checksum of a whole map file; its version.
std::uint32_t checkHeaderAndChecksum(const std::string &bytes, const std::string &path)
{
  if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    throwAt(vpHSlamException::parseError, path, 0, "not an H-SLAM map file (wrong magic)");
  }
  ByteReader header(bytes, path);
  char magic[sizeof(kMagic)];
  header.raw(magic, sizeof(magic), "the header");
  const std::uint32_t version = header.u32("the header");
  if (version < kOldestMapFileVersion || version > kMapFileVersion) {
    throwAt(vpHSlamException::unsupported, path, 0,
            "map file format version " + std::to_string(version) + ", this build reads versions " +
                std::to_string(kOldestMapFileVersion) + " to " + std::to_string(kMapFileVersion));
  }
  const std::uint32_t descriptorBytes = header.u32("the header");
  if (descriptorBytes != static_cast<std::uint32_t>(kOrbDescriptorBytes)) {
    throwAt(vpHSlamException::unsupported, path, 0,
            "descriptors of " + std::to_string(descriptorBytes) + " bytes, expected " +
                std::to_string(kOrbDescriptorBytes) + " (256-bit ORB)");
  }
  // The checksum covers everything: check it before reading any count, so a flipped bit anywhere is reported as
  // such rather than as whatever it happens to break.
  if (bytes.size() < header.offset() + kChecksumBytes) {
    throwAt(vpHSlamException::parseError, path, 0, "truncated: the file ends inside the header");
  }
  const std::size_t payload = bytes.size() - kChecksumBytes;
  if (hashBytes(bytes.data(), payload) != loadU64(reinterpret_cast<const std::uint8_t *>(bytes.data()) + payload)) {
    throwAt(vpHSlamException::parseError, path, 0, "corrupt or truncated map file: checksum mismatch");
  }
  return version;
}

//! The camera record: image size and pinhole intrinsics, checked.
MapCamera readCamera(ByteReader &r, const std::string &path)
{
  MapCamera camera;
  camera.width = r.i32("the camera");
  camera.height = r.i32("the camera");
  camera.fx = r.f64("the camera");
  camera.fy = r.f64("the camera");
  camera.cx = r.f64("the camera");
  camera.cy = r.f64("the camera");
  if (camera.width <= 0 || camera.height <= 0 || !(camera.fx > 0.) || !(camera.fy > 0.) || !std::isfinite(camera.fx) ||
      !std::isfinite(camera.fy) || !std::isfinite(camera.cx) || !std::isfinite(camera.cy)) {
    corrupt(path, "invalid camera (size or focal length)");
  }
  return camera;
}

//! The metric-frame record (version 3), checked: a unit rotation, a positive finite scale, a segment below 2^30.
void readMetricFrame(ByteReader &r, const std::string &path, MapMetricFrame &m)
{
  const std::uint8_t present = r.u8("the metric frame");
  if (present > 1) {
    corrupt(path, "invalid metric frame flag");
  }
  m.present = present == 1;
  if (!m.present) {
    return;
  }
  const std::uint8_t tagFrame = r.u8("the metric frame");
  m.segment = r.i32("the metric frame");
  m.oMw = readPose(r, path, "the metric frame");
  m.scale = r.f64("the metric frame");
  m.scaleUncertainty = r.f64("the metric frame");
  if (tagFrame > 1 || m.segment < 0 || m.segment >= (1 << 30) || !(m.scale > 0.) || !std::isfinite(m.scale) ||
      !(m.scaleUncertainty >= 0.) || !std::isfinite(m.scaleUncertainty)) {
    corrupt(path, "invalid metric frame (flag, segment or scale)");
  }
  m.tagFrame = tagFrame == 1;
}

//! One keyframe record and its points; its id joins \e ids (an id already there is an error).
void readKeyframe(ByteReader &r, const MapCamera &camera, std::uint32_t version, const std::string &path,
                  std::set<int> &ids, GlobalKeyframe &kf)
{
  kf.id = r.i32("a keyframe");
  kf.frameId = r.i32("a keyframe");
  kf.segment = r.i32("a keyframe");
  if (kf.id < 0 || kf.id > kMaxId || !ids.insert(kf.id).second) {
    corrupt(path, "keyframe id " + std::to_string(kf.id) + " out of range or repeated");
  }
  if (kf.segment < 0 || kf.segment > kMaxId) {
    corrupt(path, "keyframe segment " + std::to_string(kf.segment) + " out of range");
  }
  kf.timestamp = finite(r.f64("a keyframe"), path, "keyframe timestamp");
  kf.exposure = finite(r.f64("a keyframe"), path, "keyframe exposure");
  if (!(kf.exposure > 0.)) {
    corrupt(path, "keyframe with a non-positive exposure");
  }
  kf.cMw = readPose(r, path, "a keyframe pose");
  kf.affine.a = finite(r.f64("a keyframe"), path, "affine brightness");
  kf.affine.b = finite(r.f64("a keyframe"), path, "affine brightness");
  const std::uint8_t culled = r.u8("a keyframe");
  if (culled > 1) {
    corrupt(path, "keyframe culled flag is neither 0 nor 1");
  }
  kf.culled = culled == 1;
  const std::uint32_t points = r.u32("a point count");
  r.requireRecords(points, kPointRecordBytes, "points");
  kf.points.resize(points);
  for (GlobalPoint &p : kf.points) {
    readPoint(r, camera, version, path, p);
  }
}

//! Every point's observers are sorted ids of the file's keyframes (\e ids).
void checkObservers(const std::vector<GlobalKeyframe> &keyframes, const std::set<int> &ids, const std::string &path)
{
  for (const GlobalKeyframe &kf : keyframes) {
    for (const GlobalPoint &p : kf.points) {
      for (size_t i = 0; i < p.observers.size(); ++i) {
        if (!ids.count(p.observers[i]) || (i > 0 && p.observers[i] <= p.observers[i - 1])) {
          corrupt(path, "point observers not sorted ids of the file's keyframes");
        }
      }
    }
  }
}

//! One pose-pose edge record, between two different keyframes of the file (\e ids).
void readEdge(ByteReader &r, const std::set<int> &ids, const std::string &path, PosePoseEdge &e)
{
  e.from = r.i32("an edge");
  e.to = r.i32("an edge");
  if (!ids.count(e.from) || !ids.count(e.to) || e.from == e.to) {
    corrupt(path, "pose-pose edge between keyframes " + std::to_string(e.from) + " and " + std::to_string(e.to) +
                      " that the file does not hold");
  }
  e.toMfrom = readPose(r, path, "an edge's relative pose");
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      e.information(i, j) = finite(r.f64("an edge's information"), path, "edge information");
    }
  }
  const std::uint8_t consecutive = r.u8("an edge");
  if (consecutive > 1) {
    corrupt(path, "edge consecutive flag is neither 0 nor 1");
  }
  e.consecutive = consecutive == 1;
}
} // namespace

MapSnapshot parseMapFile(const std::string &bytes, const std::string &path)
{
  const std::uint32_t version = checkHeaderAndChecksum(bytes, path);
  const std::string body = bytes.substr(0, bytes.size() - kChecksumBytes);
  ByteReader r(body, path);
  char magic[sizeof(kMagic)];
  r.raw(magic, sizeof(magic), "the header");
  r.u32("the header");
  r.u32("the header");

  MapSnapshot map;
  map.camera = readCamera(r, path);
  map.vocabularyId = r.u64("the header");

  const std::uint32_t keyframes = r.u32("the keyframe count");
  r.requireRecords(keyframes, kKeyframeRecordBytes, "keyframes");
  map.keyframes.resize(keyframes);
  std::set<int> ids;
  for (GlobalKeyframe &kf : map.keyframes) {
    readKeyframe(r, map.camera, version, path, ids, kf);
  }
  checkObservers(map.keyframes, ids, path);

  const std::uint32_t edges = r.u32("the edge count");
  r.requireRecords(edges, kEdgeRecordBytes, "pose-pose edges");
  map.edges.resize(edges);
  for (PosePoseEdge &e : map.edges) {
    readEdge(r, ids, path, e);
  }
  if (version >= 3) {
    readMetricFrame(r, path, map.metric);
  }
  if (r.remaining() != 0) {
    corrupt(path, std::to_string(r.remaining()) + " unexpected bytes before the checksum");
  }
  return map;
}
} // namespace hslam
