// embree_bench: Embree 3 peer benchmark for bareray's "Peer benchmark contract" (see ../README.md).
//
// Traces the contract's primary rays against a sphere field with
//   * Embree's built-in sphere points (RTC_GEOMETRY_TYPE_SPHERE_POINT), and
//   * a user geometry whose intersect/occluded callbacks are an exact ray/sphere test written here
//     (the perpendicular-distance form of the contract; f32 by default, f64 with --user-precision f64),
// through rtcIntersect1/4/8/16, on 1 and 2 threads (std::thread over tiles), and prints one JSON line per
// configuration. With --ao S[,D] each camera hit also traces S cosine-weighted ambient-occlusion rays of
// length D (rtcOccluded1, or rtcOccluded4/8/16 with one hit's directions per packet), as bareray's
// `--shade ao:S,D` does. Written from the Embree API headers only.

#include <embree3/rtcore.h>
#include <pmmintrin.h>
#include <xmmintrin.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <sys/resource.h>

namespace {

// ---------------------------------------------------------------------------------------------- utilities

[[noreturn]] void die(const std::string& msg) {
  std::fprintf(stderr, "embree_bench: %s\n", msg.c_str());
  std::exit(2);
}

double now_s() {
  using clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

// Process CPU time (user + system, all threads).
double cpu_s() {
  rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_utime.tv_sec + ru.ru_stime.tv_sec + 1e-6 * (ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  if (n == 0) return 0.0;
  return (n % 2) ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::vector<double> parse_list(const std::string& s, size_t want, const char* what) {
  std::vector<double> out;
  size_t pos = 0;
  while (pos <= s.size()) {
    size_t comma = s.find(',', pos);
    if (comma == std::string::npos) comma = s.size();
    std::string tok = s.substr(pos, comma - pos);
    char* end = nullptr;
    double v = std::strtod(tok.c_str(), &end);
    if (tok.empty() || *end != '\0') die(std::string("bad number list for ") + what + ": " + s);
    out.push_back(v);
    pos = comma + 1;
  }
  if (want && out.size() != want) die(std::string("expected ") + std::to_string(want) + " numbers for " + what);
  return out;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  size_t pos = 0;
  while (pos <= s.size()) {
    size_t comma = s.find(',', pos);
    if (comma == std::string::npos) comma = s.size();
    out.push_back(s.substr(pos, comma - pos));
    pos = comma + 1;
  }
  return out;
}

// ---------------------------------------------------------------------------------------------- spheres

struct Spheres {
  // SoA, f32, in input order (primitive id = index).
  std::vector<float> x, y, z, r;
  size_t size() const { return x.size(); }
};

// The contract's splitmix64 (u64 arithmetic wraps).
struct SplitMix64 {
  uint64_t state;
  uint64_t next() {
    state += 0x9E3779B97F4A7C15ull;
    uint64_t z = state;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double u() { return double(next() >> 40) * 0x1p-24; }
};

struct FieldParams {
  uint64_t n = 1000;
  uint64_t seed = 1;
  double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
  double rmin = -1, rmax = -1;  // < 0: contract default from s
};

Spheres generate_field(const FieldParams& p) {
  double s = (p.hi[0] - p.lo[0]) / std::cbrt(double(p.n));
  double rmin = p.rmin >= 0 ? p.rmin : 0.1 * s;
  double rmax = p.rmax >= 0 ? p.rmax : 0.25 * s;
  Spheres sp;
  sp.x.resize(p.n); sp.y.resize(p.n); sp.z.resize(p.n); sp.r.resize(p.n);
  SplitMix64 rng{p.seed};
  for (uint64_t i = 0; i < p.n; ++i) {
    double ux = rng.u(), uy = rng.u(), uz = rng.u(), ur = rng.u();
    sp.x[i] = float(p.lo[0] + ux * (p.hi[0] - p.lo[0]));
    sp.y[i] = float(p.lo[1] + uy * (p.hi[1] - p.lo[1]));
    sp.z[i] = float(p.lo[2] + uz * (p.hi[2] - p.lo[2]));
    sp.r[i] = float(rmin + ur * (rmax - rmin));
  }
  return sp;
}

// .xyzr: "x y z r" per line (any whitespace), '#' starts a comment line, blank lines ignored.
// Values are parsed with strtof (correctly rounded decimal -> f32).
Spheres read_xyzr(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "r");
  if (!f) die("cannot open " + path);
  Spheres sp;
  char line[4096];
  size_t lineno = 0;
  while (std::fgets(line, sizeof line, f)) {
    ++lineno;
    char* p = line;
    while (*p == ' ' || *p == '\t') ++p;
    if (*p == '#' || *p == '\n' || *p == '\r' || *p == '\0') continue;
    float v[4];
    for (int k = 0; k < 4; ++k) {
      char* end = nullptr;
      v[k] = std::strtof(p, &end);
      if (end == p) die(path + ":" + std::to_string(lineno) + ": expected 4 numbers 'x y z r'");
      p = end;
    }
    while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n') ++p;
    if (*p != '\0') die(path + ":" + std::to_string(lineno) + ": trailing text after 'x y z r'");
    if (!(v[3] > 0.0f)) die(path + ":" + std::to_string(lineno) + ": radius must be positive");
    sp.x.push_back(v[0]); sp.y.push_back(v[1]); sp.z.push_back(v[2]); sp.r.push_back(v[3]);
  }
  std::fclose(f);
  if (sp.size() == 0) die(path + ": no spheres");
  return sp;
}

// ---------------------------------------------------------------------------------------------- camera

struct CameraParams {
  int width = 1920, height = 1080;
  double eye[3] = {0, 0, -4}, look[3] = {0, 0, 0}, up[3] = {0, 1, 0};
  double hfov = 45.0;
};

// Frame and per-pixel directions in f64, each direction rounded to f32 once (origin = eye rounded to f32).
struct Camera {
  double f[3], r[3], u[3], th;
  int W, H;
  float eye[3];
  std::vector<double> pxs, pys;  // px per column, py per row (the contract's formulas, f64)
  std::vector<float> tdx, tdy, tdz;  // --pregen: all directions computed once, outside the timing

  void pregenerate() {
    size_t n = size_t(W) * H;
    tdx.resize(n); tdy.resize(n); tdz.resize(n);
    for (int j = 0; j < H; ++j)
      for (int i = 0; i < W; ++i) {
        size_t p = size_t(j) * W + i;
        compute(i, j, tdx[p], tdy[p], tdz[p]);
      }
  }

  explicit Camera(const CameraParams& c) : W(c.width), H(c.height) {
    double fx = c.look[0] - c.eye[0], fy = c.look[1] - c.eye[1], fz = c.look[2] - c.eye[2];
    double fl = std::sqrt(fx * fx + fy * fy + fz * fz);
    if (!(fl > 0)) die("eye equals look");
    f[0] = fx / fl; f[1] = fy / fl; f[2] = fz / fl;
    // r = normalize(f x up)
    double rx = f[1] * c.up[2] - f[2] * c.up[1];
    double ry = f[2] * c.up[0] - f[0] * c.up[2];
    double rz = f[0] * c.up[1] - f[1] * c.up[0];
    double rl = std::sqrt(rx * rx + ry * ry + rz * rz);
    if (!(rl > 0)) die("up is parallel to the view direction");
    r[0] = rx / rl; r[1] = ry / rl; r[2] = rz / rl;
    // u = r x f
    u[0] = r[1] * f[2] - r[2] * f[1];
    u[1] = r[2] * f[0] - r[0] * f[2];
    u[2] = r[0] * f[1] - r[1] * f[0];
    th = std::tan(c.hfov * M_PI / 360.0);
    for (int k = 0; k < 3; ++k) eye[k] = float(c.eye[k]);
    pxs.resize(W); pys.resize(H);
    for (int i = 0; i < W; ++i) pxs[i] = (2.0 * (i + 0.5) / W - 1.0) * th;
    for (int j = 0; j < H; ++j) pys[j] = (1.0 - 2.0 * (j + 0.5) / H) * th * H / W;
  }

  inline void dir(int i, int j, float& dx, float& dy, float& dz) const {
    if (!tdx.empty()) {
      size_t p = size_t(j) * W + i;
      dx = tdx[p]; dy = tdy[p]; dz = tdz[p];
      return;
    }
    compute(i, j, dx, dy, dz);
  }

  inline void compute(int i, int j, float& dx, float& dy, float& dz) const {
    const double px = pxs[i], py = pys[j];
    double x = f[0] + px * r[0] + py * u[0];
    double y = f[1] + px * r[1] + py * u[1];
    double z = f[2] + px * r[2] + py * u[2];
    double l = std::sqrt(x * x + y * y + z * z);
    dx = float(x / l); dy = float(y / l); dz = float(z / l);
  }
};

// ---------------------------------------------------------------------------------------------- user geometry

// Exact ray/sphere, perpendicular form (Haines et al. 2019; the contract's DESIGN.md formula):
//   c = centre - o, proj = (c.d)/(d.d), p = c - proj d, l2 = p.p; miss if l2 > r2;
//   td = sqrt((r2 - l2)/(d.d)); t0 = proj - td, t1 = proj + td; smallest t in [tnear, tfar].
// A ray starting inside gets t1, the exit point. Ties at equal t go to the lower primitive id, so the
// result does not depend on the BVH traversal order.
template <typename R>
inline bool sphere_hit(const float* o, const float* d, float cx, float cy, float cz, float rad, float tnear,
                       float tfar, unsigned prim, unsigned cur_prim, float& t_out) {
  R ox = o[0], oy = o[1], oz = o[2], dx = d[0], dy = d[1], dz = d[2];
  R ccx = R(cx) - ox, ccy = R(cy) - oy, ccz = R(cz) - oz;
  R dd = dx * dx + dy * dy + dz * dz;
  R proj = (ccx * dx + ccy * dy + ccz * dz) / dd;
  R px = ccx - proj * dx, py = ccy - proj * dy, pz = ccz - proj * dz;
  R l2 = px * px + py * py + pz * pz;
  R r2 = R(rad) * R(rad);
  if (!(l2 <= r2)) return false;
  R td = std::sqrt((r2 - l2) / dd);
  float t0 = float(proj - td), t1 = float(proj + td);
  float t;
  if (t0 >= tnear && t0 <= tfar) t = t0;
  else if (t1 >= tnear && t1 <= tfar) t = t1;
  else return false;
  if (t == tfar && prim >= cur_prim) return false;
  t_out = t;
  return true;
}

struct UserData {
  const Spheres* sp;
  bool f64;
  bool packet_kernel;  // use the branch-free packet callback for N = 4/8/16 (f32 only)
};

void user_bounds(const RTCBoundsFunctionArguments* a) {
  const UserData* ud = static_cast<const UserData*>(a->geometryUserPtr);
  const Spheres& s = *ud->sp;
  unsigned i = a->primID;
  RTCBounds* b = a->bounds_o;
  b->lower_x = s.x[i] - s.r[i]; b->lower_y = s.y[i] - s.r[i]; b->lower_z = s.z[i] - s.r[i];
  b->upper_x = s.x[i] + s.r[i]; b->upper_y = s.y[i] + s.r[i]; b->upper_z = s.z[i] + s.r[i];
  // f32 rounding of centre +- r may cut the sphere by an ulp: widen by one ulp outward.
  b->lower_x = std::nextafter(b->lower_x, -INFINITY); b->lower_y = std::nextafter(b->lower_y, -INFINITY);
  b->lower_z = std::nextafter(b->lower_z, -INFINITY);
  b->upper_x = std::nextafter(b->upper_x, INFINITY); b->upper_y = std::nextafter(b->upper_y, INFINITY);
  b->upper_z = std::nextafter(b->upper_z, INFINITY);
}

// Packet version of user_intersect for N = 4, 8, 16 and f32: the same formula and operation order as
// sphere_hit<float>, written without branches over the lanes (selects instead), so that GCC vectorises it
// over Embree's SoA packet layout. IEEE add/mul/div/sqrt and no contraction: the results are bit-identical
// to the scalar loop (checked by the checksums of api 1 vs 4/8/16).
template <unsigned N>
void user_intersect_f32_packet(const RTCIntersectFunctionNArguments* a) {
  const UserData* ud = static_cast<const UserData*>(a->geometryUserPtr);
  const Spheres& s = *ud->sp;
  const unsigned i = a->primID;
  const float cx = s.x[i], cy = s.y[i], cz = s.z[i], rad = s.r[i];
  const float r2 = rad * rad;
  float* rp = reinterpret_cast<float*>(a->rayhit);
  const float* ox = rp + 0 * N; const float* oy = rp + 1 * N; const float* oz = rp + 2 * N;
  const float* tn = rp + 3 * N;
  const float* dx = rp + 4 * N; const float* dy = rp + 5 * N; const float* dz = rp + 6 * N;
  float* tf = rp + 8 * N;
  float* ngx = rp + 12 * N; float* ngy = rp + 13 * N; float* ngz = rp + 14 * N;
  float* hu = rp + 15 * N; float* hv = rp + 16 * N;
  unsigned* prim = reinterpret_cast<unsigned*>(rp + 17 * N);
  unsigned* geom = reinterpret_cast<unsigned*>(rp + 18 * N);
  unsigned* inst = reinterpret_cast<unsigned*>(rp + 19 * N);
  const int* valid = a->valid;
  const unsigned gid = a->geomID, iid = a->context->instID[0];
#pragma GCC ivdep
  for (unsigned k = 0; k < N; ++k) {
    float ccx = cx - ox[k], ccy = cy - oy[k], ccz = cz - oz[k];
    float dd = dx[k] * dx[k] + dy[k] * dy[k] + dz[k] * dz[k];
    float proj = (ccx * dx[k] + ccy * dy[k] + ccz * dz[k]) / dd;
    float px = ccx - proj * dx[k], py = ccy - proj * dy[k], pz = ccz - proj * dz[k];
    float l2 = px * px + py * py + pz * pz;
    bool inr = l2 <= r2;
    float td = std::sqrt(inr ? (r2 - l2) / dd : 0.0f);
    float t0 = proj - td, t1 = proj + td;
    float tfar = tf[k], tnear = tn[k];
    bool ok0 = (t0 >= tnear) & (t0 <= tfar), ok1 = (t1 >= tnear) & (t1 <= tfar);
    float t = ok0 ? t0 : t1;
    unsigned cur = geom[k] == RTC_INVALID_GEOMETRY_ID ? 0xFFFFFFFFu : prim[k];
    bool hit = (valid[k] == -1) & inr & (ok0 | ok1) & !((t == tfar) & (i >= cur));
    tf[k] = hit ? t : tfar;
    ngx[k] = hit ? ox[k] + t * dx[k] - cx : ngx[k];
    ngy[k] = hit ? oy[k] + t * dy[k] - cy : ngy[k];
    ngz[k] = hit ? oz[k] + t * dz[k] - cz : ngz[k];
    hu[k] = hit ? 0.0f : hu[k];
    hv[k] = hit ? 0.0f : hv[k];
    prim[k] = hit ? i : prim[k];
    geom[k] = hit ? gid : geom[k];
    inst[k] = hit ? iid : inst[k];
  }
}

void user_intersect(const RTCIntersectFunctionNArguments* a) {
  const UserData* ud0 = static_cast<const UserData*>(a->geometryUserPtr);
  if (ud0->packet_kernel && !ud0->f64) {
    switch (a->N) {
      case 4: return user_intersect_f32_packet<4>(a);
      case 8: return user_intersect_f32_packet<8>(a);
      case 16: return user_intersect_f32_packet<16>(a);
      default: break;
    }
  }
  const UserData* ud = static_cast<const UserData*>(a->geometryUserPtr);
  const Spheres& s = *ud->sp;
  const unsigned i = a->primID, N = a->N;
  const float cx = s.x[i], cy = s.y[i], cz = s.z[i], rad = s.r[i];
  RTCRayN* ray = RTCRayHitN_RayN(a->rayhit, N);
  RTCHitN* hit = RTCRayHitN_HitN(a->rayhit, N);
  for (unsigned k = 0; k < N; ++k) {
    if (a->valid[k] != -1) continue;
    float o[3] = {RTCRayN_org_x(ray, N, k), RTCRayN_org_y(ray, N, k), RTCRayN_org_z(ray, N, k)};
    float d[3] = {RTCRayN_dir_x(ray, N, k), RTCRayN_dir_y(ray, N, k), RTCRayN_dir_z(ray, N, k)};
    float& tfar = RTCRayN_tfar(ray, N, k);
    unsigned& cur = RTCHitN_primID(hit, N, k);
    unsigned cur_prim = (RTCHitN_geomID(hit, N, k) == RTC_INVALID_GEOMETRY_ID) ? 0xFFFFFFFFu : cur;
    float t;
    bool h = ud->f64 ? sphere_hit<double>(o, d, cx, cy, cz, rad, RTCRayN_tnear(ray, N, k), tfar, i, cur_prim, t)
                     : sphere_hit<float>(o, d, cx, cy, cz, rad, RTCRayN_tnear(ray, N, k), tfar, i, cur_prim, t);
    if (!h) continue;
    tfar = t;
    RTCHitN_Ng_x(hit, N, k) = o[0] + t * d[0] - cx;
    RTCHitN_Ng_y(hit, N, k) = o[1] + t * d[1] - cy;
    RTCHitN_Ng_z(hit, N, k) = o[2] + t * d[2] - cz;
    RTCHitN_u(hit, N, k) = 0.0f;
    RTCHitN_v(hit, N, k) = 0.0f;
    cur = i;
    RTCHitN_geomID(hit, N, k) = a->geomID;
    RTCHitN_instID(hit, N, k, 0) = a->context->instID[0];
  }
}

// Packet version of user_occluded for N = 4, 8, 16 and f32 (the same test as user_intersect_f32_packet, any
// hit: tfar = -inf), branch-free over the lanes so that GCC vectorises it. Same formula and operation order as
// sphere_hit<float>, so the answers are the scalar loop's (checked: same ao_open with --user-kernel scalar).
// The test is written out again rather than shared with user_intersect_f32_packet: one inline function for
// both (same counts) kept GCC from vectorising this loop, and AO ran 1.3x slower (1e5 field, 480x270, api 16).
template <unsigned N>
void user_occluded_f32_packet(const RTCOccludedFunctionNArguments* a) {
  const UserData* ud = static_cast<const UserData*>(a->geometryUserPtr);
  const Spheres& s = *ud->sp;
  const unsigned i = a->primID;
  const float cx = s.x[i], cy = s.y[i], cz = s.z[i], rad = s.r[i];
  const float r2 = rad * rad;
  float* rp = reinterpret_cast<float*>(a->ray);
  const float* ox = rp + 0 * N; const float* oy = rp + 1 * N; const float* oz = rp + 2 * N;
  const float* tn = rp + 3 * N;
  const float* dx = rp + 4 * N; const float* dy = rp + 5 * N; const float* dz = rp + 6 * N;
  float* tf = rp + 8 * N;
  const int* valid = a->valid;
#pragma GCC ivdep
  for (unsigned k = 0; k < N; ++k) {
    float ccx = cx - ox[k], ccy = cy - oy[k], ccz = cz - oz[k];
    float dd = dx[k] * dx[k] + dy[k] * dy[k] + dz[k] * dz[k];
    float proj = (ccx * dx[k] + ccy * dy[k] + ccz * dz[k]) / dd;
    float px = ccx - proj * dx[k], py = ccy - proj * dy[k], pz = ccz - proj * dz[k];
    float l2 = px * px + py * py + pz * pz;
    bool inr = l2 <= r2;
    float td = std::sqrt(inr ? (r2 - l2) / dd : 0.0f);
    float t0 = proj - td, t1 = proj + td;
    float tfar = tf[k], tnear = tn[k];
    bool ok0 = (t0 >= tnear) & (t0 <= tfar), ok1 = (t1 >= tnear) & (t1 <= tfar);
    // sphere_hit's tie rule (t == tfar and prim >= cur_prim) with cur_prim = 0xFFFFFFFF, as user_occluded.
    float t = ok0 ? t0 : t1;
    bool hit = (valid[k] == -1) & inr & (ok0 | ok1) & !((t == tfar) & (i == 0xFFFFFFFFu));
    tf[k] = hit ? -INFINITY : tfar;
  }
}

void user_occluded(const RTCOccludedFunctionNArguments* a) {
  const UserData* ud = static_cast<const UserData*>(a->geometryUserPtr);
  if (ud->packet_kernel && !ud->f64) {
    switch (a->N) {
      case 4: return user_occluded_f32_packet<4>(a);
      case 8: return user_occluded_f32_packet<8>(a);
      case 16: return user_occluded_f32_packet<16>(a);
      default: break;
    }
  }
  const Spheres& s = *ud->sp;
  const unsigned i = a->primID, N = a->N;
  for (unsigned k = 0; k < N; ++k) {
    if (a->valid[k] != -1) continue;
    float o[3] = {RTCRayN_org_x(a->ray, N, k), RTCRayN_org_y(a->ray, N, k), RTCRayN_org_z(a->ray, N, k)};
    float d[3] = {RTCRayN_dir_x(a->ray, N, k), RTCRayN_dir_y(a->ray, N, k), RTCRayN_dir_z(a->ray, N, k)};
    float& tfar = RTCRayN_tfar(a->ray, N, k);
    float t;
    bool h = ud->f64 ? sphere_hit<double>(o, d, s.x[i], s.y[i], s.z[i], s.r[i], RTCRayN_tnear(a->ray, N, k),
                                          tfar, i, 0xFFFFFFFFu, t)
                     : sphere_hit<float>(o, d, s.x[i], s.y[i], s.z[i], s.r[i], RTCRayN_tnear(a->ray, N, k),
                                         tfar, i, 0xFFFFFFFFu, t);
    if (h) tfar = -INFINITY;
  }
}

// ---------------------------------------------------------------------------------------------- scene

std::atomic<int64_t> g_bytes{0}, g_peak{0};

bool memory_monitor(void*, ssize_t bytes, bool) {
  int64_t v = g_bytes.fetch_add(bytes) + bytes;
  int64_t p = g_peak.load();
  while (v > p && !g_peak.compare_exchange_weak(p, v)) {}
  return true;
}

RTCScene make_scene(RTCDevice dev, const Spheres& sp, bool user, UserData* ud, RTCBuildQuality q,
                    std::vector<float>& points_storage) {
  RTCScene scene = rtcNewScene(dev);
  rtcSetSceneBuildQuality(scene, q);
  rtcSetSceneFlags(scene, RTC_SCENE_FLAG_NONE);
  RTCGeometry g;
  if (!user) {
    g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_SPHERE_POINT);
    // Shared buffer (x,y,z,r) f32, filled outside the timed region; Embree reads it during the build.
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, points_storage.data(), 0,
                               4 * sizeof(float), sp.size());
  } else {
    g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, unsigned(sp.size()));
    rtcSetGeometryUserData(g, ud);
    rtcSetGeometryBoundsFunction(g, user_bounds, ud);
    rtcSetGeometryIntersectFunction(g, user_intersect);
    rtcSetGeometryOccludedFunction(g, user_occluded);
  }
  rtcSetGeometryBuildQuality(g, q);
  rtcCommitGeometry(g);
  rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
  return scene;
}

// ---------------------------------------------------------------------------------------------- render

struct Frame {
  std::vector<float> t;    // per pixel, inf on miss
  std::vector<int32_t> id; // per pixel, -1 on miss
  std::vector<int32_t> ao; // --ao: per pixel, how many of its S occlusion rays are open (0 on a miss);
                           // the pixel's value is ao / S
};

// ---------------------------------------------------------------------------------------------- ambient occlusion

// --ao S[,D]: at each camera hit, S cosine-weighted directions over the hemisphere around the sphere's outward
// normal, each an occlusion ray of length D (inf: unbounded).
struct AoParams {
  int samples = 0;  // 0: off (camera rays only)
  float distance = INFINITY;
  const Spheres* sp = nullptr;
};

// Departure (tnear stays 0): the origin is put on the hit sphere, c + (r + e) n with n = normalize(p - c) and
// p = o + t d the camera hit, i.e. moved out along the normal by e = max(AO_EPS * r, AO_EPS_ABS * m), m the
// largest of |cx|, |cy|, |cz| and r. In exact arithmetic no direction with d.n >= 0 from there meets the
// departure sphere; e must beat the f32 rounding of the origin (~1e-7 absolute on the [-1, 1] field). Measured
// on the contract field (160x90, S = 16), counting occlusion rays that meet their own sphere in f64: origin
// p + 1e-4 r n (p not put back on the sphere, so the camera t's rounding stays in): 64 rays at 1e5 and 4608
// at 1e6; c + (r + e) n: none at 1e5, 1e6 and 1e7 with 1e-4 r (with 1e-5 r: 3360 at 1e6; with 3e-5 r: 480
// at 1e7). The absolute floor (4 f32 ulps at 1) is for larger coordinates and smaller spheres than those.
// e is far below the distances between spheres that matter (open counts with 1e-3 r differ by a few rays in
// 1e5). bareray instead skips the departure sphere by its id and starts at the hit point.
constexpr float AO_EPS = 1e-4f;
constexpr float AO_EPS_ABS = 0x1p-21f;

inline uint64_t mix64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// One hit's departure: origin c + (r + e) n and the frame around n (Duff et al. 2017, "Building an orthonormal
// basis, revisited"; the same as bareray's `around`).
struct AoHit {
  float org[3];
  float n[3], tx[3], bt[3];
  SplitMix64 rng;  // the pixel's stream: sample k uses its k-th output, whatever the api or thread
};

inline void ao_hit(const AoParams& ao, const float o[3], const float d[3], float t, unsigned prim, size_t pixel,
                   AoHit& h) {
  const Spheres& s = *ao.sp;
  const float p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
  float nx = p[0] - s.x[prim], ny = p[1] - s.y[prim], nz = p[2] - s.z[prim];
  const float inv = 1.0f / std::sqrt(nx * nx + ny * ny + nz * nz);
  nx *= inv; ny *= inv; nz *= inv;
  h.n[0] = nx; h.n[1] = ny; h.n[2] = nz;
  const float m = std::max(std::max(std::fabs(s.x[prim]), std::fabs(s.y[prim])), std::max(std::fabs(s.z[prim]), s.r[prim]));
  const float re = s.r[prim] + std::max(AO_EPS * s.r[prim], AO_EPS_ABS * m);
  h.org[0] = s.x[prim] + re * nx; h.org[1] = s.y[prim] + re * ny; h.org[2] = s.z[prim] + re * nz;
  const float sign = nz < 0.0f ? -1.0f : 1.0f;
  const float a = -1.0f / (sign + nz), b = nx * ny * a;
  h.tx[0] = 1.0f + sign * nx * nx * a; h.tx[1] = sign * b; h.tx[2] = -(sign * nx);
  h.bt[0] = b; h.bt[1] = sign + ny * ny * a; h.bt[2] = -ny;
  h.rng.state = mix64(uint64_t(pixel) + 0x243F6A8885A308D3ull);
}

// The next sample direction of the hit (Malley's method: a uniform point on the unit disc, r = sqrt(u1),
// phi = 2 pi u2, lifted to the hemisphere, z = sqrt(1 - u1); density cos(theta)/pi), u1 and u2 the top two
// 24-bit fields of one splitmix64 output; normalised in f32.
inline void ao_dir(AoHit& h, float& dx, float& dy, float& dz) {
  const uint64_t bits = h.rng.next();
  const float u1 = float(bits >> 40) * 0x1p-24f, u2 = float((bits >> 16) & 0xFFFFFFu) * 0x1p-24f;
  const float r = std::sqrt(u1), z = std::sqrt(1.0f - u1);
  float sn, cs;
  sincosf(6.283185307179586f * u2, &sn, &cs);
  const float x = r * cs, y = r * sn;
  float wx = h.tx[0] * x + h.bt[0] * y + h.n[0] * z;
  float wy = h.tx[1] * x + h.bt[1] * y + h.n[1] * z;
  float wz = h.tx[2] * x + h.bt[2] * y + h.n[2] * z;
  const float inv = 1.0f / std::sqrt(wx * wx + wy * wy + wz * wz);
  dx = wx * inv; dy = wy * inv; dz = wz * inv;
}

// S occlusion rays of one hit, one rtcOccluded1 each; returns how many are open.
inline int ao_trace_1(RTCScene scene, RTCIntersectContext* ctx, const AoParams& ao, AoHit& h) {
  int open = 0;
  for (int k = 0; k < ao.samples; ++k) {
    RTCRay r;
    r.org_x = h.org[0]; r.org_y = h.org[1]; r.org_z = h.org[2];
    ao_dir(h, r.dir_x, r.dir_y, r.dir_z);
    r.tnear = 0.0f; r.tfar = ao.distance; r.time = 0.0f;
    r.mask = 0xFFFFFFFFu; r.id = 0; r.flags = 0;
    rtcOccluded1(scene, ctx, &r);
    open += r.tfar != -INFINITY;
  }
  return open;
}

template <int K> struct OccPacket;
template <> struct OccPacket<4> {
  using R = RTCRay4;
  static void occ(const int* v, RTCScene s, RTCIntersectContext* c, R* r) { rtcOccluded4(v, s, c, r); }
};
template <> struct OccPacket<8> {
  using R = RTCRay8;
  static void occ(const int* v, RTCScene s, RTCIntersectContext* c, R* r) { rtcOccluded8(v, s, c, r); }
};
template <> struct OccPacket<16> {
  using R = RTCRay16;
  static void occ(const int* v, RTCScene s, RTCIntersectContext* c, R* r) { rtcOccluded16(v, s, c, r); }
};

// S occlusion rays of one hit in packets of K directions (one origin): ceil(S/K) rtcOccludedK calls, the last
// one's lanes past S inactive (valid = 0). Returns how many are open.
template <int K>
inline int ao_trace_k(RTCScene scene, RTCIntersectContext* ctx, const AoParams& ao, AoHit& h) {
  alignas(64) typename OccPacket<K>::R r;
  alignas(64) int valid[K];
  int open = 0;
  for (int k0 = 0; k0 < ao.samples; k0 += K) {
    const int count = std::min(K, ao.samples - k0);
    for (int l = 0; l < K; ++l) {
      valid[l] = l < count ? -1 : 0;
      r.org_x[l] = h.org[0]; r.org_y[l] = h.org[1]; r.org_z[l] = h.org[2];
      if (l < count) ao_dir(h, r.dir_x[l], r.dir_y[l], r.dir_z[l]);
      else { r.dir_x[l] = h.n[0]; r.dir_y[l] = h.n[1]; r.dir_z[l] = h.n[2]; }
      r.tnear[l] = 0.0f; r.tfar[l] = ao.distance; r.time[l] = 0.0f;
      r.mask[l] = 0xFFFFFFFFu; r.id[l] = 0; r.flags[l] = 0;
    }
    OccPacket<K>::occ(valid, scene, ctx, &r);
    for (int l = 0; l < count; ++l) open += r.tfar[l] != -INFINITY;
  }
  return open;
}

constexpr int TILE_W = 32, TILE_H = 32;

template <int K> struct Packet;
template <> struct Packet<4> {
  using RH = RTCRayHit4; static constexpr int BW = 2, BH = 2;
  static void isect(const int* v, RTCScene s, RTCIntersectContext* c, RH* r) { rtcIntersect4(v, s, c, r); }
};
template <> struct Packet<8> {
  using RH = RTCRayHit8; static constexpr int BW = 4, BH = 2;
  static void isect(const int* v, RTCScene s, RTCIntersectContext* c, RH* r) { rtcIntersect8(v, s, c, r); }
};
template <> struct Packet<16> {
  using RH = RTCRayHit16; static constexpr int BW = 4, BH = 4;
  static void isect(const int* v, RTCScene s, RTCIntersectContext* c, RH* r) { rtcIntersect16(v, s, c, r); }
};

inline void store(Frame& fr, int W, int i, int j, unsigned geom, unsigned prim, float tfar) {
  size_t p = size_t(j) * W + i;
  if (geom == RTC_INVALID_GEOMETRY_ID) { fr.t[p] = INFINITY; fr.id[p] = -1; }
  else { fr.t[p] = tfar; fr.id[p] = int32_t(prim); }
}

void tile_1(RTCScene scene, const Camera& cam, Frame& fr, const AoParams& ao, int x0, int y0, int x1, int y1) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  RTCIntersectContext actx;  // occlusion rays: the default (incoherent) context
  rtcInitIntersectContext(&actx);
  for (int j = y0; j < y1; ++j)
    for (int i = x0; i < x1; ++i) {
      RTCRayHit rh;
      rh.ray.org_x = cam.eye[0]; rh.ray.org_y = cam.eye[1]; rh.ray.org_z = cam.eye[2];
      cam.dir(i, j, rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z);
      rh.ray.tnear = 0.0f; rh.ray.tfar = INFINITY; rh.ray.time = 0.0f;
      rh.ray.mask = 0xFFFFFFFFu; rh.ray.id = 0; rh.ray.flags = 0;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID; rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene, &ctx, &rh);
      store(fr, cam.W, i, j, rh.hit.geomID, rh.hit.primID, rh.ray.tfar);
      if (ao.samples) {
        const size_t p = size_t(j) * cam.W + i;
        int open = 0;
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
          const float o[3] = {rh.ray.org_x, rh.ray.org_y, rh.ray.org_z};
          const float d[3] = {rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z};
          AoHit h;
          ao_hit(ao, o, d, rh.ray.tfar, rh.hit.primID, p, h);
          open = ao_trace_1(scene, &actx, ao, h);
        }
        fr.ao[p] = open;
      }
    }
}

template <int K>
void tile_k(RTCScene scene, const Camera& cam, Frame& fr, const AoParams& ao, int x0, int y0, int x1, int y1) {
  using P = Packet<K>;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  RTCIntersectContext actx;  // occlusion rays: the default (incoherent) context
  rtcInitIntersectContext(&actx);
  alignas(64) typename P::RH rh;
  alignas(64) int valid[K];
  for (int by = y0; by < y1; by += P::BH)
    for (int bx = x0; bx < x1; bx += P::BW) {
      for (int l = 0; l < K; ++l) {
        int i = bx + l % P::BW, j = by + l / P::BW;
        bool ok = i < x1 && j < y1;
        valid[l] = ok ? -1 : 0;
        rh.ray.org_x[l] = cam.eye[0]; rh.ray.org_y[l] = cam.eye[1]; rh.ray.org_z[l] = cam.eye[2];
        if (ok) cam.dir(i, j, rh.ray.dir_x[l], rh.ray.dir_y[l], rh.ray.dir_z[l]);
        else { rh.ray.dir_x[l] = 0; rh.ray.dir_y[l] = 0; rh.ray.dir_z[l] = 1; }
        rh.ray.tnear[l] = 0.0f; rh.ray.tfar[l] = INFINITY; rh.ray.time[l] = 0.0f;
        rh.ray.mask[l] = 0xFFFFFFFFu; rh.ray.id[l] = 0; rh.ray.flags[l] = 0;
        rh.hit.geomID[l] = RTC_INVALID_GEOMETRY_ID; rh.hit.primID[l] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][l] = RTC_INVALID_GEOMETRY_ID;
      }
      P::isect(valid, scene, &ctx, &rh);
      for (int l = 0; l < K; ++l)
        if (valid[l]) store(fr, cam.W, bx + l % P::BW, by + l / P::BW, rh.hit.geomID[l], rh.hit.primID[l], rh.ray.tfar[l]);
      if (ao.samples)
        for (int l = 0; l < K; ++l) {
          if (!valid[l]) continue;
          const size_t p = size_t(by + l / P::BW) * cam.W + (bx + l % P::BW);
          int open = 0;
          if (rh.hit.geomID[l] != RTC_INVALID_GEOMETRY_ID) {
            const float o[3] = {rh.ray.org_x[l], rh.ray.org_y[l], rh.ray.org_z[l]};
            const float d[3] = {rh.ray.dir_x[l], rh.ray.dir_y[l], rh.ray.dir_z[l]};
            AoHit h;
            ao_hit(ao, o, d, rh.ray.tfar[l], rh.hit.primID[l], p, h);
            open = ao_trace_k<K>(scene, &actx, ao, h);
          }
          fr.ao[p] = open;
        }
    }
}

void render(RTCScene scene, const Camera& cam, Frame& fr, const AoParams& ao, int api, int threads) {
  const int tx = (cam.W + TILE_W - 1) / TILE_W, ty = (cam.H + TILE_H - 1) / TILE_H;
  const int ntiles = tx * ty;
  std::atomic<int> next{0};
  auto worker = [&]() {
    // Embree asks for flush-to-zero / denormals-are-zero on every tracing thread.
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
    for (;;) {
      int k = next.fetch_add(1, std::memory_order_relaxed);
      if (k >= ntiles) break;
      int x0 = (k % tx) * TILE_W, y0 = (k / tx) * TILE_H;
      int x1 = std::min(x0 + TILE_W, cam.W), y1 = std::min(y0 + TILE_H, cam.H);
      switch (api) {
        case 1: tile_1(scene, cam, fr, ao, x0, y0, x1, y1); break;
        case 4: tile_k<4>(scene, cam, fr, ao, x0, y0, x1, y1); break;
        case 8: tile_k<8>(scene, cam, fr, ao, x0, y0, x1, y1); break;
        case 16: tile_k<16>(scene, cam, fr, ao, x0, y0, x1, y1); break;
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& th : pool) th.join();
}

// FNV-1a 64 over the per-pixel int32 ids (little-endian bytes, row-major, row 0 at the top).
uint64_t checksum_ids(const std::vector<int32_t>& ids) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (int32_t v : ids) {
    uint32_t u = uint32_t(v);
    for (int b = 0; b < 4; ++b) { h ^= (u >> (8 * b)) & 0xFF; h *= 0x100000001b3ull; }
  }
  return h;
}

void write_dump(const std::string& path, const Camera& cam, const Frame& fr) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) die("cannot write " + path);
  const char magic[8] = {'B', 'R', 'D', 'U', 'M', 'P', '1', '\0'};
  uint32_t wh[2] = {uint32_t(cam.W), uint32_t(cam.H)};
  std::fwrite(magic, 1, 8, f);
  std::fwrite(wh, 4, 2, f);
  std::fwrite(fr.t.data(), 4, fr.t.size(), f);
  std::fwrite(fr.id.data(), 4, fr.id.size(), f);
  std::fclose(f);
}

void usage() {
  std::puts(
      "usage: embree_bench [options]\n"
      "scene (one of):\n"
      "  --count N            contract sphere field of N spheres (default 1000)\n"
      "  --xyzr FILE          read spheres 'x y z r' per line ('#' comments)\n"
      "field options: --seed S (1)  --box x0,x1 | x0,y0,z0,x1,y1,z1 (-1,1)  --rmin R --rmax R (0.1 s, 0.25 s)\n"
      "camera: --width W (1920) --height H (1080) --eye x,y,z (0,0,-4) --look x,y,z (0,0,0)\n"
      "        --up x,y,z (0,1,0) --hfov DEG (45)\n"
      "matrix: --geometry points,user (both)  --api 1,4,8,16 (all)  --threads 1,2 (1,2)\n"
      "        --reps R (5 render repetitions; median reported)  --build-reps B (3; median)\n"
      "        --quality low|medium|high (medium)  --user-precision f32|f64 (f32)\n"
      "        --user-kernel packet|scalar (packet: branch-free SIMD callbacks for packets, f32 only)\n"
      "ambient occlusion: --ao S[,D]  at each camera hit, S cosine-weighted occlusion rays of length D\n"
      "        (default inf) from the hit sphere's surface (origin c + (r + e) n, e = max(1e-4 r,\n"
      "        2^-21 max(|c|, r)), tnear 0),\n"
      "        rtcOccluded1 for api 1, else rtcOccluded4/8/16 with one hit's directions per packet; timed\n"
      "        with the camera rays, mrays_per_s counts both\n"
      "output: --dump FILE   per-pixel t and id of the FIRST configuration run (see README)\n"
      "        --write-xyzr FILE  write the spheres ('%.9g', round-trips f32) and continue\n"
      "        --verbose     Embree device verbose=1 (prints the ISA chosen)\n"
      "        --isa I       Embree device isa=I (sse2, sse4.2, avx, avx2, avx512; default: the best the CPU has)\n"
      "timing: --pregen      compute all ray directions once before timing (default: generated per ray,\n"
      "                      inside the timed loop, as a renderer does)");
}

}  // namespace

int main(int argc, char** argv) {
  FieldParams fp;
  CameraParams cp;
  std::string xyzr, dump, write_xyzr;
  std::vector<std::string> geoms = {"points", "user"};
  std::vector<int> apis = {1, 4, 8, 16}, thread_counts = {1, 2};
  int reps = 5, build_reps = 3;
  RTCBuildQuality quality = RTC_BUILD_QUALITY_MEDIUM;
  std::string quality_name = "medium";
  bool user_f64 = false, verbose = false, pregen = false;
  std::string isa;
  std::string user_kernel = "packet";
  AoParams ao;

  for (int a = 1; a < argc; ++a) {
    std::string k = argv[a];
    auto val = [&]() -> std::string {
      if (a + 1 >= argc) die("missing value for " + k);
      return argv[++a];
    };
    if (k == "--count") fp.n = uint64_t(std::strtod(val().c_str(), nullptr));
    else if (k == "--xyzr") xyzr = val();
    else if (k == "--seed") fp.seed = std::strtoull(val().c_str(), nullptr, 10);
    else if (k == "--box") {
      std::string v = val();
      auto b = parse_list(v, 0, "--box");
      if (b.size() == 2) for (int i = 0; i < 3; ++i) { fp.lo[i] = b[0]; fp.hi[i] = b[1]; }
      else if (b.size() == 6) for (int i = 0; i < 3; ++i) { fp.lo[i] = b[i]; fp.hi[i] = b[3 + i]; }
      else die("--box takes x0,x1 or x0,y0,z0,x1,y1,z1");
    }
    else if (k == "--rmin") fp.rmin = std::strtod(val().c_str(), nullptr);
    else if (k == "--rmax") fp.rmax = std::strtod(val().c_str(), nullptr);
    else if (k == "--width") cp.width = std::atoi(val().c_str());
    else if (k == "--height") cp.height = std::atoi(val().c_str());
    else if (k == "--eye") { auto v = parse_list(val(), 3, "--eye"); std::copy(v.begin(), v.end(), cp.eye); }
    else if (k == "--look") { auto v = parse_list(val(), 3, "--look"); std::copy(v.begin(), v.end(), cp.look); }
    else if (k == "--up") { auto v = parse_list(val(), 3, "--up"); std::copy(v.begin(), v.end(), cp.up); }
    else if (k == "--hfov") cp.hfov = std::strtod(val().c_str(), nullptr);
    else if (k == "--geometry") geoms = split(val());
    else if (k == "--api") { apis.clear(); for (auto& s : split(val())) apis.push_back(std::atoi(s.c_str())); }
    else if (k == "--threads") { thread_counts.clear(); for (auto& s : split(val())) thread_counts.push_back(std::atoi(s.c_str())); }
    else if (k == "--reps") reps = std::atoi(val().c_str());
    else if (k == "--build-reps") build_reps = std::atoi(val().c_str());
    else if (k == "--quality") {
      quality_name = val();
      if (quality_name == "low") quality = RTC_BUILD_QUALITY_LOW;
      else if (quality_name == "medium") quality = RTC_BUILD_QUALITY_MEDIUM;
      else if (quality_name == "high") quality = RTC_BUILD_QUALITY_HIGH;
      else die("--quality low|medium|high");
    }
    else if (k == "--user-precision") {
      std::string v = val();
      if (v == "f64") user_f64 = true; else if (v == "f32") user_f64 = false; else die("--user-precision f32|f64");
    }
    else if (k == "--dump") dump = val();
    else if (k == "--write-xyzr") write_xyzr = val();
    else if (k == "--user-kernel") {
      user_kernel = val();
      if (user_kernel != "packet" && user_kernel != "scalar") die("--user-kernel packet|scalar");
    }
    else if (k == "--verbose") verbose = true;
    else if (k == "--isa") isa = val();
    else if (k == "--pregen") pregen = true;
    else if (k == "--ao") {
      std::string v = val();
      auto parts = split(v);
      if (parts.size() > 2) die("--ao takes S or S,D");
      char* end = nullptr;
      long n = std::strtol(parts[0].c_str(), &end, 10);
      if (parts[0].empty() || *end != '\0' || n < 1 || n > 1000000) die("--ao: S must be a positive integer, got " + parts[0]);
      ao.samples = int(n);
      if (parts.size() == 2) {
        double d = std::strtod(parts[1].c_str(), &end);
        if (parts[1].empty() || *end != '\0' || !(d > 0)) die("--ao: D must be a positive number (or inf), got " + parts[1]);
        ao.distance = float(d);
      }
    }
    else if (k == "-h" || k == "--help") { usage(); return 0; }
    else die("unknown option " + k + " (try --help)");
  }
  for (auto& g : geoms) if (g != "points" && g != "user") die("--geometry: points or user, got " + g);
  for (int a : apis) if (a != 1 && a != 4 && a != 8 && a != 16) die("--api: 1, 4, 8 or 16");
  for (int t : thread_counts) if (t < 1) die("--threads must be >= 1");
  if (cp.width < 1 || cp.height < 1) die("bad resolution");
  if (reps < 1 || build_reps < 1) die("reps must be >= 1");

  double t_gen0 = now_s();
  Spheres sp = xyzr.empty() ? generate_field(fp) : read_xyzr(xyzr);
  double t_gen = now_s() - t_gen0;
  std::fprintf(stderr, "spheres: %zu (%s, %.3f s)\n", sp.size(), xyzr.empty() ? "generated" : xyzr.c_str(), t_gen);

  if (!write_xyzr.empty()) {
    FILE* f = std::fopen(write_xyzr.c_str(), "w");
    if (!f) die("cannot write " + write_xyzr);
    std::fprintf(f, "# x y z r (f32, %%.9g); %zu spheres\n", sp.size());
    for (size_t i = 0; i < sp.size(); ++i)
      std::fprintf(f, "%.9g %.9g %.9g %.9g\n", sp.x[i], sp.y[i], sp.z[i], sp.r[i]);
    std::fclose(f);
  }

  std::vector<float> points(sp.size() * 4);
  for (size_t i = 0; i < sp.size(); ++i) {
    points[4 * i] = sp.x[i]; points[4 * i + 1] = sp.y[i]; points[4 * i + 2] = sp.z[i]; points[4 * i + 3] = sp.r[i];
  }
  UserData ud{&sp, user_f64, user_kernel == "packet"};
  ao.sp = &sp;
  Camera cam(cp);
  if (pregen) cam.pregenerate();
  const double nrays = double(cam.W) * cam.H;
  bool dumped = false;

  for (int threads : thread_counts) {
    // One device per thread count: "threads=T" limits Embree's own (TBB) build threads to T as well.
    std::string cfg = "threads=" + std::to_string(threads) + (verbose ? ",verbose=1" : "") +
                      (isa.empty() ? "" : ",isa=" + isa);
    RTCDevice dev = rtcNewDevice(cfg.c_str());
    if (!dev) die("rtcNewDevice failed");
    rtcSetDeviceMemoryMonitorFunction(dev, memory_monitor, nullptr);
    for (const std::string& geom : geoms) {
      bool user = geom == "user";
      // Build: median over build_reps fresh scenes; the last one is kept for rendering.
      std::vector<double> builds, build_cpus;
      RTCScene scene = nullptr;
      int64_t bytes = 0;
      for (int b = 0; b < build_reps; ++b) {
        if (scene) rtcReleaseScene(scene);
        int64_t before = g_bytes.load();
        scene = make_scene(dev, sp, user, &ud, quality, points);
        double c0 = cpu_s(), t0 = now_s();
        rtcCommitScene(scene);
        builds.push_back(now_s() - t0);
        build_cpus.push_back(cpu_s() - c0);
        if (rtcGetDeviceError(dev) != RTC_ERROR_NONE) die("Embree error during commit");
        bytes = g_bytes.load() - before;
      }
      double build_s = median(builds);
      for (int api : apis) {
        Frame fr;
        fr.t.assign(size_t(cam.W) * cam.H, NAN);
        fr.id.assign(size_t(cam.W) * cam.H, -2);
        if (ao.samples) fr.ao.assign(size_t(cam.W) * cam.H, -1);
        render(scene, cam, fr, ao, api, threads);  // warm-up (not timed)
        std::vector<double> times, cpus;
        for (int r = 0; r < reps; ++r) {
          double c0 = cpu_s(), t0 = now_s();
          render(scene, cam, fr, ao, api, threads);
          times.push_back(now_s() - t0);
          cpus.push_back(cpu_s() - c0);
        }
        double sec = median(times);
        uint64_t hits = 0;
        double tsum = 0;
        for (size_t p = 0; p < fr.id.size(); ++p)
          if (fr.id[p] >= 0) { ++hits; tsum += fr.t[p]; }
        uint64_t ck = checksum_ids(fr.id);
        // --ao: every hit traces exactly S occlusion rays; the open ones are summed from the per-pixel counts.
        const uint64_t ao_rays = hits * uint64_t(ao.samples);
        uint64_t ao_open = 0;
        for (int32_t v : fr.ao) ao_open += uint64_t(v);
        const double all_rays = nrays + double(ao_rays);
        std::printf(
            "{\"tracer\":\"embree\",\"geometry\":\"%s\",\"api\":\"%d\",\"threads\":%d,\"spheres\":%zu,"
            "\"build_s\":%.6f,\"build_cpu_s\":%.6f,\"seconds\":%.6f,\"mrays_per_s\":%.3f,\"checksum\":\"%016" PRIx64 "\","
            "\"hits\":%" PRIu64 ",\"t_sum\":%.9g,\"width\":%d,\"height\":%d,\"reps\":%d,\"seconds_min\":%.6f,"
            "\"seconds_max\":%.6f,\"cpu_s\":%.6f,\"build_s_all\":[",
            geom.c_str(), api, threads, sp.size(), build_s, median(build_cpus), sec, all_rays / sec / 1e6, ck, hits, tsum, cam.W, cam.H,
            reps, *std::min_element(times.begin(), times.end()), *std::max_element(times.begin(), times.end()), median(cpus));
        for (size_t b = 0; b < builds.size(); ++b) std::printf("%s%.6f", b ? "," : "", builds[b]);
        std::printf("]");
        if (ao.samples) {
          // ao_distance null = infinity (JSON has no inf). ao_checksum: FNV-1a 64 over the per-pixel open counts
          // (int32, as "checksum" over the ids): equal across apis when every occlusion ray gets the same answer.
          std::printf(",\"camera_rays\":%.0f,\"rays\":%.0f,\"ao_samples\":%d,", nrays, all_rays, ao.samples);
          if (std::isinf(ao.distance)) std::printf("\"ao_distance\":null,");
          else std::printf("\"ao_distance\":%.9g,", double(ao.distance));
          std::printf("\"ao_rays\":%" PRIu64 ",\"ao_open\":%" PRIu64 ",\"ao_open_share\":%.6f,"
                      "\"ao_mrays_per_s\":%.3f,\"ao_checksum\":\"%016" PRIx64 "\",\"ao_origin\":\"c+(r+max(%g*r,%g*max(|c|,r)))*n\"",
                      ao_rays, ao_open, ao_rays ? double(ao_open) / double(ao_rays) : 0.0, double(ao_rays) / sec / 1e6,
                      checksum_ids(fr.ao), double(AO_EPS), double(AO_EPS_ABS));
        }
        std::printf(",\"embree_bytes\":%" PRId64 ",\"quality\":\"%s\",\"raygen\":\"%s\"%s,\"embree\":\"%s\"}\n", bytes,
                    quality_name.c_str(), pregen ? "pregen" : "inline", user ? (user_f64 ? ",\"user_precision\":\"f64\",\"user_kernel\":\"scalar\"" : (ud.packet_kernel ? ",\"user_precision\":\"f32\",\"user_kernel\":\"packet\"" : ",\"user_precision\":\"f32\",\"user_kernel\":\"scalar\"")) : "",
                    RTC_VERSION_STRING);
        std::fflush(stdout);
        if (!dump.empty() && !dumped) {
          write_dump(dump, cam, fr);
          dumped = true;
          std::fprintf(stderr, "dump: %s (%s, api %d, %d threads)\n", dump.c_str(), geom.c_str(), api, threads);
        }
      }
      rtcReleaseScene(scene);
    }
    rtcReleaseDevice(dev);
  }
  return 0;
}
