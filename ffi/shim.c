/* meshlight's C shim over Embree's C API: see shim.h. Compiles against Embree 3 and 4. */
#include "shim.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef ML_EMBREE_MAJOR
#error "ML_EMBREE_MAJOR must be 3 or 4 (the build script defines it)"
#endif

#if ML_EMBREE_MAJOR == 4
#include <embree4/rtcore.h>
#elif ML_EMBREE_MAJOR == 3
#include <embree3/rtcore.h>
#else
#error "ML_EMBREE_MAJOR must be 3 or 4"
#endif

#if defined(__x86_64__) || defined(__i386__) || defined(_M_X64)
#include <pmmintrin.h>
#include <xmmintrin.h>
/* Embree wants flush-to-zero and denormals-are-zero on every thread that calls it; restore the
 * caller's mode afterwards so Rust code on the same thread is not affected. */
#define ML_FTZ_BEGIN                                                                               \
  unsigned int ml_saved_csr_ = _mm_getcsr();                                                       \
  _mm_setcsr(ml_saved_csr_ | 0x8040u)
#define ML_FTZ_END _mm_setcsr(ml_saved_csr_)
#else
#define ML_FTZ_BEGIN (void)0
#define ML_FTZ_END (void)0
#endif

/* Compile-time layout checks; the Rust side asserts the same numbers on its mirrors. */
_Static_assert(sizeof(ml_segment) == ML_SEGMENT_SIZE, "ml_segment layout");
_Static_assert(sizeof(ml_ray) == ML_RAY_SIZE, "ml_ray layout");
_Static_assert(sizeof(ml_hit) == ML_HIT_SIZE, "ml_hit layout");
_Static_assert(_Alignof(ml_segment) == 4 && _Alignof(ml_ray) == 4 && _Alignof(ml_hit) == 4,
               "ml_* alignment");

struct ml_scene {
  RTCDevice device;
  RTCScene scene;
  atomic_int error_claimed; /* first error wins the message slot */
  atomic_int error_ready;   /* the message is written */
  char error[256];
};

int ml_embree_major(void) { return ML_EMBREE_MAJOR; }

/* The message of the last error Embree reported on this thread: a query's error is the
 * calling thread's own (Embree keeps an error code per device and thread), never another
 * thread's or an earlier call's. */
static _Thread_local char thread_error[256];

static void on_device_error(void *user, enum RTCError code, const char *str) {
  ml_scene *s = (ml_scene *)user;
  int expected = 0;
  if (s == NULL || code == RTC_ERROR_NONE) {
    return;
  }
  snprintf(thread_error, sizeof thread_error, "Embree error %d: %s", (int)code, str ? str : "");
  if (atomic_compare_exchange_strong(&s->error_claimed, &expected, 1)) {
    snprintf(s->error, sizeof s->error, "Embree error %d: %s", (int)code, str ? str : "");
    atomic_store(&s->error_ready, 1);
  }
}

static void write_err(char *err, size_t errlen, const char *msg) {
  if (err != NULL && errlen > 0) {
    snprintf(err, errlen, "%s", msg);
  }
}

ml_scene *ml_scene_new(const float *vertices, size_t nv, const uint32_t *indices, size_t nt,
                       int quality, bool robust, char *err, size_t errlen) {
  if ((nv > 0 && vertices == NULL) || (nt > 0 && indices == NULL) || quality < 0 ||
      quality > 2) {
    write_err(err, errlen, "invalid arguments to ml_scene_new");
    return NULL;
  }
  for (size_t i = 0; i < 3 * nt; ++i) {
    if (indices[i] >= nv) {
      write_err(err, errlen, "triangle index out of range in ml_scene_new");
      return NULL;
    }
  }
  ml_scene *s = (ml_scene *)calloc(1, sizeof(ml_scene));
  if (s == NULL) {
    write_err(err, errlen, "out of memory");
    return NULL;
  }
  ML_FTZ_BEGIN;
  s->device = rtcNewDevice("verbose=0");
  if (s->device == NULL) {
    char msg[128];
    snprintf(msg, sizeof msg, "rtcNewDevice failed (Embree error %d)", (int)rtcGetDeviceError(NULL));
    write_err(err, errlen, msg);
    free(s);
    ML_FTZ_END;
    return NULL;
  }
  rtcSetDeviceErrorFunction(s->device, on_device_error, s);

  enum RTCBuildQuality q = quality == 0   ? RTC_BUILD_QUALITY_LOW
                           : quality == 1 ? RTC_BUILD_QUALITY_MEDIUM
                                          : RTC_BUILD_QUALITY_HIGH;
  s->scene = rtcNewScene(s->device);
  if (s->scene != NULL) {
    rtcSetSceneBuildQuality(s->scene, q);
    rtcSetSceneFlags(s->scene, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    if (nt > 0) {
      RTCGeometry g = rtcNewGeometry(s->device, RTC_GEOMETRY_TYPE_TRIANGLE);
      if (g != NULL) {
        float *vb = (float *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
                                                     RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv);
        uint32_t *ib = (uint32_t *)rtcSetNewGeometryBuffer(
            g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), nt);
        if (vb == NULL || ib == NULL) {
          /* A failed allocation: neither commit nor attach a geometry without its buffers. */
          rtcReleaseGeometry(g);
          ML_FTZ_END;
          write_err(err, errlen,
                    atomic_load(&s->error_ready) ? s->error
                                                 : "Embree could not allocate the geometry buffers");
          ml_scene_free(s);
          return NULL;
        }
        memcpy(vb, vertices, 3 * nv * sizeof(float));
        memcpy(ib, indices, 3 * nt * sizeof(uint32_t));
        rtcSetGeometryBuildQuality(g, q);
        rtcCommitGeometry(g);
        rtcAttachGeometry(s->scene, g);
        rtcReleaseGeometry(g);
      } else {
        ML_FTZ_END;
        write_err(err, errlen, atomic_load(&s->error_ready) ? s->error : "rtcNewGeometry failed");
        ml_scene_free(s);
        return NULL;
      }
    }
    rtcCommitScene(s->scene);
  }
  ML_FTZ_END;
  if (s->scene == NULL || atomic_load(&s->error_ready)) {
    write_err(err, errlen, atomic_load(&s->error_ready) ? s->error : "rtcNewScene failed");
    ml_scene_free(s);
    return NULL;
  }
  return s;
}

void ml_scene_free(ml_scene *s) {
  if (s == NULL) {
    return;
  }
  if (s->scene != NULL) {
    rtcReleaseScene(s->scene);
  }
  if (s->device != NULL) {
    rtcReleaseDevice(s->device);
  }
  free(s);
}

void ml_scene_error(const ml_scene *s, char *buf, size_t len) {
  if (buf == NULL || len == 0) {
    return;
  }
  buf[0] = '\0';
  if (s != NULL && atomic_load(&((ml_scene *)s)->error_ready)) {
    snprintf(buf, len, "%s", s->error);
  }
}

/* Per-call query arguments, whose type differs between Embree 3 and 4. */
#if ML_EMBREE_MAJOR == 4
typedef struct {
  struct RTCOccludedArguments occ;
  struct RTCIntersectArguments isect;
} ml_args;
static void ml_args_init(ml_args *a) {
  rtcInitOccludedArguments(&a->occ);
  rtcInitIntersectArguments(&a->isect);
  a->occ.flags = RTC_RAY_QUERY_FLAG_INCOHERENT;
  a->isect.flags = RTC_RAY_QUERY_FLAG_INCOHERENT;
}
#define ML_OCCLUDED1(s, a, r) rtcOccluded1((s), (r), &(a)->occ)
#define ML_OCCLUDEDN(N, v, s, a, r) rtcOccluded##N((v), (s), (r), &(a)->occ)
#define ML_INTERSECT1(s, a, r) rtcIntersect1((s), (r), &(a)->isect)
#define ML_INTERSECTN(N, v, s, a, r) rtcIntersect##N((v), (s), (r), &(a)->isect)
#else
typedef struct {
  struct RTCIntersectContext ctx;
} ml_args;
static void ml_args_init(ml_args *a) {
  rtcInitIntersectContext(&a->ctx);
  a->ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
}
#define ML_OCCLUDED1(s, a, r) rtcOccluded1((s), &(a)->ctx, (r))
#define ML_OCCLUDEDN(N, v, s, a, r) rtcOccluded##N((v), (s), &(a)->ctx, (r))
#define ML_INTERSECT1(s, a, r) rtcIntersect1((s), &(a)->ctx, (r))
#define ML_INTERSECTN(N, v, s, a, r) rtcIntersect##N((v), (s), &(a)->ctx, (r))
#endif

/* Writes segment g as a single ray (parametric: dir = b - a). */
static void segment_ray1(struct RTCRay *r, const ml_segment *g, float t_min, float t_max) {
  r->org_x = g->a[0];
  r->org_y = g->a[1];
  r->org_z = g->a[2];
  r->tnear = t_min;
  r->dir_x = g->b[0] - g->a[0];
  r->dir_y = g->b[1] - g->a[1];
  r->dir_z = g->b[2] - g->a[2];
  r->time = 0.0f;
  r->tfar = t_max;
  r->mask = 0xFFFFFFFFu;
  r->id = 0;
  r->flags = 0;
}

static void camera_ray1(struct RTCRayHit *rh, const ml_ray *q) {
  rh->ray.org_x = q->org[0];
  rh->ray.org_y = q->org[1];
  rh->ray.org_z = q->org[2];
  rh->ray.tnear = q->tnear;
  rh->ray.dir_x = q->dir[0];
  rh->ray.dir_y = q->dir[1];
  rh->ray.dir_z = q->dir[2];
  rh->ray.time = 0.0f;
  rh->ray.tfar = q->tfar;
  rh->ray.mask = 0xFFFFFFFFu;
  rh->ray.id = 0;
  rh->ray.flags = 0;
  rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh->hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

static void write_hit(ml_hit *out, unsigned int geom, unsigned int prim, float t) {
  if (geom == RTC_INVALID_GEOMETRY_ID) {
    out->t = INFINITY;
    out->prim = ML_MISS;
  } else {
    out->t = t;
    out->prim = prim;
  }
}

static void occluded_single(RTCScene sc, ml_args *a, const ml_segment *segs, size_t n, float t0,
                            float t1, bool *out) {
  for (size_t i = 0; i < n; ++i) {
    struct RTCRay r;
    segment_ray1(&r, &segs[i], t0, t1);
    ML_OCCLUDED1(sc, a, &r);
    out[i] = r.tfar < 0.0f; /* Embree sets tfar to -inf on a hit */
  }
}

static void intersect_single(RTCScene sc, ml_args *a, const ml_ray *rays, size_t n, ml_hit *out) {
  for (size_t i = 0; i < n; ++i) {
    struct RTCRayHit rh;
    camera_ray1(&rh, &rays[i]);
    ML_INTERSECT1(sc, a, &rh);
    write_hit(&out[i], rh.hit.geomID, rh.hit.primID, rh.ray.tfar);
  }
}

/* Packets of N rays in SoA form; the tail packet masks its unused lanes. */
#define ML_DEFINE_PACKETS(N)                                                                       \
  static void occluded_packet##N(RTCScene sc, ml_args *a, const ml_segment *segs, size_t n,      \
                                 float t0, float t1, bool *out) {                                  \
    for (size_t base = 0; base < n; base += N) {                                                   \
      struct RTCRay##N r;                                                                          \
      _Alignas(64) int valid[N];                                                                   \
      size_t m = n - base < N ? n - base : N;                                                      \
      for (size_t i = 0; i < N; ++i) {                                                             \
        const ml_segment *g = &segs[base + (i < m ? i : 0)];                                       \
        valid[i] = i < m ? -1 : 0;                                                                 \
        r.org_x[i] = g->a[0];                                                                      \
        r.org_y[i] = g->a[1];                                                                      \
        r.org_z[i] = g->a[2];                                                                      \
        r.tnear[i] = t0;                                                                           \
        r.dir_x[i] = g->b[0] - g->a[0];                                                            \
        r.dir_y[i] = g->b[1] - g->a[1];                                                            \
        r.dir_z[i] = g->b[2] - g->a[2];                                                            \
        r.time[i] = 0.0f;                                                                          \
        r.tfar[i] = t1;                                                                            \
        r.mask[i] = 0xFFFFFFFFu;                                                                   \
        r.id[i] = (unsigned int)i;                                                                 \
        r.flags[i] = 0;                                                                            \
      }                                                                                            \
      ML_OCCLUDEDN(N, valid, sc, a, &r);                                                           \
      for (size_t i = 0; i < m; ++i) {                                                             \
        out[base + i] = r.tfar[i] < 0.0f;                                                          \
      }                                                                                            \
    }                                                                                              \
  }                                                                                                \
  static void intersect_packet##N(RTCScene sc, ml_args *a, const ml_ray *rays, size_t n,         \
                                  ml_hit *out) {                                                   \
    for (size_t base = 0; base < n; base += N) {                                                   \
      struct RTCRayHit##N rh;                                                                      \
      _Alignas(64) int valid[N];                                                                   \
      size_t m = n - base < N ? n - base : N;                                                      \
      for (size_t i = 0; i < N; ++i) {                                                             \
        const ml_ray *q = &rays[base + (i < m ? i : 0)];                                           \
        valid[i] = i < m ? -1 : 0;                                                                 \
        rh.ray.org_x[i] = q->org[0];                                                               \
        rh.ray.org_y[i] = q->org[1];                                                               \
        rh.ray.org_z[i] = q->org[2];                                                               \
        rh.ray.tnear[i] = q->tnear;                                                                \
        rh.ray.dir_x[i] = q->dir[0];                                                               \
        rh.ray.dir_y[i] = q->dir[1];                                                               \
        rh.ray.dir_z[i] = q->dir[2];                                                               \
        rh.ray.time[i] = 0.0f;                                                                     \
        rh.ray.tfar[i] = q->tfar;                                                                  \
        rh.ray.mask[i] = 0xFFFFFFFFu;                                                              \
        rh.ray.id[i] = (unsigned int)i;                                                            \
        rh.ray.flags[i] = 0;                                                                       \
        rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;                                                \
        rh.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;                                                \
        rh.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;                                             \
      }                                                                                            \
      ML_INTERSECTN(N, valid, sc, a, &rh);                                                         \
      for (size_t i = 0; i < m; ++i) {                                                             \
        write_hit(&out[base + i], rh.hit.geomID[i], rh.hit.primID[i], rh.ray.tfar[i]);             \
      }                                                                                            \
    }                                                                                              \
  }

ML_DEFINE_PACKETS(4)
ML_DEFINE_PACKETS(8)
ML_DEFINE_PACKETS(16)

#if ML_EMBREE_MAJOR == 3
/* Streams of single rays (rtcOccluded1M / rtcIntersect1M), removed in Embree 4. */
#define ML_STREAM_CHUNK 256
static void occluded_stream(RTCScene sc, ml_args *a, const ml_segment *segs, size_t n, float t0,
                            float t1, bool *out) {
  struct RTCRay rays[ML_STREAM_CHUNK];
  for (size_t base = 0; base < n; base += ML_STREAM_CHUNK) {
    size_t m = n - base < ML_STREAM_CHUNK ? n - base : ML_STREAM_CHUNK;
    for (size_t i = 0; i < m; ++i) {
      segment_ray1(&rays[i], &segs[base + i], t0, t1);
    }
    rtcOccluded1M(sc, &a->ctx, rays, (unsigned int)m, sizeof(struct RTCRay));
    for (size_t i = 0; i < m; ++i) {
      out[base + i] = rays[i].tfar < 0.0f;
    }
  }
}

static void intersect_stream(RTCScene sc, ml_args *a, const ml_ray *rays, size_t n, ml_hit *out) {
  struct RTCRayHit rh[ML_STREAM_CHUNK];
  for (size_t base = 0; base < n; base += ML_STREAM_CHUNK) {
    size_t m = n - base < ML_STREAM_CHUNK ? n - base : ML_STREAM_CHUNK;
    for (size_t i = 0; i < m; ++i) {
      camera_ray1(&rh[i], &rays[base + i]);
    }
    rtcIntersect1M(sc, &a->ctx, rh, (unsigned int)m, sizeof(struct RTCRayHit));
    for (size_t i = 0; i < m; ++i) {
      write_hit(&out[base + i], rh[i].hit.geomID, rh[i].hit.primID, rh[i].ray.tfar);
    }
  }
}
#endif

/* Before a query: forget this thread's earlier error on the device. */
static void status_before(const ml_scene *s) {
  thread_error[0] = '\0';
  (void)rtcGetDeviceError(s->device);
}

/* After a query: this thread's error on the device during the call, if any (and it is reset). */
static int status_after(const ml_scene *s) {
  enum RTCError code = rtcGetDeviceError(s->device);
  if (code == RTC_ERROR_NONE) {
    return ML_OK;
  }
  if (thread_error[0] == '\0') {
    snprintf(thread_error, sizeof thread_error, "Embree error %d", (int)code);
  }
  return ML_ERR_EMBREE;
}

void ml_thread_error(char *buf, size_t len) {
  if (buf != NULL && len > 0) {
    snprintf(buf, len, "%s", thread_error);
  }
}

int ml_occluded(const ml_scene *s, const ml_segment *segs, size_t n, float t_min, float t_max,
                int mode, bool *out) {
  if (s == NULL || (n > 0 && (segs == NULL || out == NULL))) {
    return ML_ERR_ARGUMENT;
  }
#if ML_EMBREE_MAJOR != 3
  if (mode == ML_MODE_STREAM) {
    return ML_ERR_UNSUPPORTED;
  }
#endif
  if (mode < ML_MODE_SINGLE || mode > ML_MODE_STREAM) {
    return ML_ERR_ARGUMENT;
  }
  ml_args a;
  ml_args_init(&a);
  status_before(s);
  ML_FTZ_BEGIN;
  switch (mode) {
  case ML_MODE_SINGLE:
    occluded_single(s->scene, &a, segs, n, t_min, t_max, out);
    break;
  case ML_MODE_PACKET4:
    occluded_packet4(s->scene, &a, segs, n, t_min, t_max, out);
    break;
  case ML_MODE_PACKET8:
    occluded_packet8(s->scene, &a, segs, n, t_min, t_max, out);
    break;
  case ML_MODE_PACKET16:
    occluded_packet16(s->scene, &a, segs, n, t_min, t_max, out);
    break;
#if ML_EMBREE_MAJOR == 3
  case ML_MODE_STREAM:
    occluded_stream(s->scene, &a, segs, n, t_min, t_max, out);
    break;
#endif
  default:
    break;
  }
  ML_FTZ_END;
  return status_after(s);
}

int ml_intersect(const ml_scene *s, const ml_ray *rays, size_t n, int mode, ml_hit *out) {
  if (s == NULL || (n > 0 && (rays == NULL || out == NULL))) {
    return ML_ERR_ARGUMENT;
  }
#if ML_EMBREE_MAJOR != 3
  if (mode == ML_MODE_STREAM) {
    return ML_ERR_UNSUPPORTED;
  }
#endif
  if (mode < ML_MODE_SINGLE || mode > ML_MODE_STREAM) {
    return ML_ERR_ARGUMENT;
  }
  ml_args a;
  ml_args_init(&a);
  status_before(s);
  ML_FTZ_BEGIN;
  switch (mode) {
  case ML_MODE_SINGLE:
    intersect_single(s->scene, &a, rays, n, out);
    break;
  case ML_MODE_PACKET4:
    intersect_packet4(s->scene, &a, rays, n, out);
    break;
  case ML_MODE_PACKET8:
    intersect_packet8(s->scene, &a, rays, n, out);
    break;
  case ML_MODE_PACKET16:
    intersect_packet16(s->scene, &a, rays, n, out);
    break;
#if ML_EMBREE_MAJOR == 3
  case ML_MODE_STREAM:
    intersect_stream(s->scene, &a, rays, n, out);
    break;
#endif
  default:
    break;
  }
  ML_FTZ_END;
  return status_after(s);
}
