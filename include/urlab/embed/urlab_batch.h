/* The C interface of liburlab_batch.so: a batch of environments of a scene inside the caller's
 * process (urlab/embed/in_process_batch.h), for programs in other languages (the Python client
 * loads it with ctypes: urlab_client.inproc). Plain C types only.
 *
 * Every function returning int returns 0 on success and -1 on failure, with the reason (naming
 * the file and line, or the field) in `error` (at most error_size bytes, NUL-terminated; may be
 * NULL). Arrays are row-major, environment after environment; doubles are the machine's.
 *
 * Threading: a handle's calls are serialised by a lock of the handle (calls from several threads
 * take turns). Several handles may be open in a process, each with its own threads. A step runs
 * on the calling thread and the batch's stepping workers.
 */
#ifndef URLAB_EMBED_URLAB_BATCH_H_
#define URLAB_EMBED_URLAB_BATCH_H_

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define URLAB_BATCH_API __attribute__((visibility("default")))

/* The interface's version: a caller checks it before anything else (2: copy_model, copy_data
 * and mujoco_version added; 3: urlab_batch_options.raw_actions). */
#define URLAB_BATCH_ABI 3
URLAB_BATCH_API int urlab_batch_abi(void);

typedef struct urlab_batch urlab_batch;

/* What urlab_batch_open takes (urlab run's --envs, --threads, --no-auto-reset,
 * --max-episode-steps, --reset-noise, --seed, --raw-actions). */
typedef struct urlab_batch_options {
  int envs;              /* at least 1 */
  int threads;           /* stepping threads; 0: the machine's cores */
  int auto_reset;        /* nonzero: gymnasium's next-step autoreset */
  int max_episode_steps; /* physics steps; 0: an episode ends only when it diverges */
  double reset_noise;    /* uniform noise at each reset, 0 or more */
  int has_seed;          /* nonzero: environment i starts with seed + i; 0: the scene's seed */
  uint64_t seed;
  const char* log_level; /* trace, debug, info, warn, error or off; NULL: warn */
  int raw_actions;       /* nonzero: the actions are the controls (the scene's controllers off);
                          * 0: every environment runs the scene's controllers on them */
} urlab_batch_options;

/* The sizes of an open batch. */
typedef struct urlab_batch_sizes {
  int envs, threads, nu, nq, nv, nsensordata, obs_size;
  double timestep;
} urlab_batch_sizes;

/* Where a step's or reset's outputs go (each array may be NULL: not wanted):
 * obs envs x obs_size, done / reset envs bytes (0 or 1), time envs, episode_steps envs. */
typedef struct urlab_batch_outputs {
  double* obs;
  uint8_t* done;
  uint8_t* reset;
  double* time;
  uint32_t* episode_steps;
  double seconds; /* set: the wall time of the step on the stepping thread */
} urlab_batch_outputs;

/* Loads `scene` (a scene .yaml or an MJCF .xml) and returns a handle, or NULL with the reason. */
URLAB_BATCH_API urlab_batch* urlab_batch_open(const char* scene, const urlab_batch_options* options,
                                              char* error, size_t error_size);
URLAB_BATCH_API void urlab_batch_close(urlab_batch* batch);

URLAB_BATCH_API int urlab_batch_get_sizes(urlab_batch* batch, urlab_batch_sizes* sizes);
/* Each action's range (nu values each): its controller's target range (the joint's range under a
 * PD controller), else the actuator's ctrlrange; -inf / +inf without one. */
URLAB_BATCH_API int urlab_batch_action_bounds(urlab_batch* batch, double* low, double* high);
/* The actuators' names, NUL-separated, into `names` (at most size bytes); the bytes needed. */
URLAB_BATCH_API size_t urlab_batch_actuator_names(urlab_batch* batch, char* names, size_t size);

/* One step: actions envs x nu (finite); reset NULL or one flag per environment (those reset
 * instead of stepping); n_steps physics steps with the actions held. */
URLAB_BATCH_API int urlab_batch_step(urlab_batch* batch, const double* actions,
                                     const uint8_t* reset, int n_steps, urlab_batch_outputs* out,
                                     char* error, size_t error_size);
/* Resets `count` environments listed in `envs` (count 0: all), envs[k] from seeds[k] when
 * has_seed[k] is nonzero (seeds / has_seed may be NULL: none). */
URLAB_BATCH_API int urlab_batch_reset(urlab_batch* batch, const int* envs, int count,
                                      const uint64_t* seeds, const uint8_t* has_seed,
                                      urlab_batch_outputs* out, char* error, size_t error_size);
URLAB_BATCH_API int urlab_batch_set_auto_reset(urlab_batch* batch, int on);

/* For MuJoCo's own tools (its Python bindings: urlab_client's `model` and `data(i)`), reading
 * environment `env` while nothing steps it. The pointers are MuJoCo's types (this header does not
 * include MuJoCo's), for the MuJoCo urlab_batch_mujoco_version names (mj_version()).
 * - urlab_batch_copy_model: a copy (mj_copyModel) of the environment's model (its own when the
 *   scene randomises), an mjModel* the caller owns and frees with mj_deleteModel; NULL with the
 *   reason on failure.
 * - urlab_batch_copy_data: the environment's whole mjData (state, what its last step computed,
 *   contacts; mj_copyData) into `data`, an mjData* made (mj_makeData) for a model of the same
 *   sizes (urlab_batch_copy_model's copy). */
URLAB_BATCH_API int urlab_batch_mujoco_version(void);
URLAB_BATCH_API void* urlab_batch_copy_model(urlab_batch* batch, int env, char* error,
                                             size_t error_size);
URLAB_BATCH_API int urlab_batch_copy_data(urlab_batch* batch, int env, void* data, char* error,
                                          size_t error_size);

#ifdef __cplusplus
}
#endif

#endif /* URLAB_EMBED_URLAB_BATCH_H_ */
