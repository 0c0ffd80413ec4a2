/* meshlight's C shim over Embree's C API.
 *
 * One call carries a whole batch of queries, so the Rust side pays the FFI crossing once per
 * batch and Embree gets packets or streams. The shim compiles against Embree 3
 * (<embree3/rtcore.h>, Debian 12) and Embree 4 (<embree4/rtcore.h>, Debian 13); the build
 * script defines ML_EMBREE_MAJOR to say which. */
#ifndef MESHLIGHT_SHIM_H
#define MESHLIGHT_SHIM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* A segment from a to b; the shim tests hits at parameters t in [t_min, t_max] of a + t (b - a). */
typedef struct ml_segment {
  float a[3];
  float b[3];
} ml_segment;

/* A ray: hits at distances t in [tnear, tfar] along org + t dir. */
typedef struct ml_ray {
  float org[3];
  float dir[3];
  float tnear;
  float tfar;
} ml_ray;

/* The nearest hit of a ray: prim is the triangle index given at build, or ML_MISS. */
typedef struct ml_hit {
  float t;
  uint32_t prim;
} ml_hit;

#define ML_MISS 0xFFFFFFFFu

/* How a batch is handed to Embree. Streams exist in Embree 3 only. */
enum ml_mode {
  ML_MODE_SINGLE = 0,
  ML_MODE_PACKET4 = 1,
  ML_MODE_PACKET8 = 2,
  ML_MODE_PACKET16 = 3,
  ML_MODE_STREAM = 4
};

/* Return codes. */
enum ml_status {
  ML_OK = 0,
  ML_ERR_EMBREE = 1,      /* Embree reported an error: ml_thread_error() has its text */
  ML_ERR_UNSUPPORTED = 2, /* the mode does not exist in this Embree version */
  ML_ERR_ARGUMENT = 3     /* a null pointer or an out-of-range value */
};

typedef struct ml_scene ml_scene;

/* Sizes the Rust side checks its #[repr(C)] mirrors against. */
#define ML_SEGMENT_SIZE 24
#define ML_RAY_SIZE 32
#define ML_HIT_SIZE 8

/* The Embree major version the shim was compiled against (3 or 4). */
int ml_embree_major(void);

/* Builds a scene of nt triangles over nv vertices (xyz floats, indices into them).
 * quality: 0 low, 1 medium, 2 high; robust: Embree's robust (watertight) traversal.
 * On failure returns NULL and writes a message into err (errlen bytes, NUL-terminated). */
ml_scene *ml_scene_new(const float *vertices, size_t nv, const uint32_t *indices, size_t nt,
                       int quality, bool robust, char *err, size_t errlen);

/* Releases the scene and its device. */
void ml_scene_free(ml_scene *scene);

/* The first error Embree reported on this scene's device since it was built (empty if none). */
void ml_scene_error(const ml_scene *scene, char *buf, size_t len);

/* The error Embree reported on the calling thread during its last ml_occluded or ml_intersect
 * that returned ML_ERR_EMBREE (empty if none). */
void ml_thread_error(char *buf, size_t len);

/* For each segment, whether a triangle lies on it within [t_min, t_max]; out[i] true = blocked. */
int ml_occluded(const ml_scene *scene, const ml_segment *segments, size_t n, float t_min,
                float t_max, int mode, bool *out);

/* For each ray, its nearest hit. */
int ml_intersect(const ml_scene *scene, const ml_ray *rays, size_t n, int mode, ml_hit *out);

#endif
