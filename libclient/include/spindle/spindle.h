/* libspindle: the client library of the Spindle volumetric display daemon.
 *
 * A client connects to spindled, creates buffers (vertex data), display
 * lists (retained drawing commands referring to buffers) and layers (a
 * list's placement in the shared volume), and commits: everything set since
 * the last commit shows together, from one volume on. Geometry conventions
 * (volume space, y up along the rotation axis, unit = display radius) are
 * those of docs/design.md and docs/protocol.md.
 *
 * Threading: a struct spindle and its objects are used from one thread at a
 * time. Errors: functions returning int return 0 (or a count) on success and
 * a negative errno on failure; constructors return NULL and set errno. Once
 * the daemon has sent a fatal error or the connection broke, every call
 * returns -EPIPE (constructors NULL with errno EPIPE) and
 * spindle_get_error() tells why. The library never prints, unless a log
 * handler is installed with spindle_set_log_handler(). */
#ifndef SPINDLE_SPINDLE_H
#define SPINDLE_SPINDLE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* SPINDLE_PROTOCOL_VERSION and the daemon's fatal error codes (enum
 * spindle_error_code), generated from the protocol's description; the
 * library's version (SPINDLE_VERSION_*, and spindle_library_version() for
 * the library a program runs with). */
#include <spindle/spindle-errors.h>
#include <spindle/spindle-version.h>

/* Default socket path, used when neither a path nor SPINDLE_SOCKET is given. */
#define SPINDLE_DEFAULT_SOCKET "/run/spindle/spindle.sock"

/* The most bytes spindle_buffer_create_inline() takes. */
#define SPINDLE_INLINE_MAX 65516

struct spindle;
struct spindle_buffer;
struct spindle_list;
struct spindle_layer;

/* The display device, as the daemon reports it at connection. */
struct spindle_device_info {
	uint32_t width;          /* pixels per image row (W) */
	uint32_t height;         /* rows per image (H) */
	uint32_t images_per_rev; /* images shown per revolution (N) */
	bool mirrored;           /* volumes hold N/2 images */
	float half_height;       /* h: the volume is x^2+z^2 <= 1, |y| <= h */
	float rpm;               /* nominal rotor speed */
	char name[64];           /* device description, NUL-terminated */
};

/* Daemon and device state (spindle_get_status()). Counters count from
 * the daemon's start. A commit that leaves the whole scene (every visible
 * layer of every client) as it was in the last volume rendered renders
 * and uploads nothing: volumes_skipped counts such scenes (commits made
 * while a render runs, or waits to start, are taken together, as one scene). */
struct spindle_status {
	float rpm;    /* measured rotor speed, 0 when not turning */
	bool locked;  /* sync estimator locked to the rotor */
	bool blanked; /* projector dark */
	bool projector_present;
	uint64_t volumes_shown;    /* volumes swapped in on the projector */
	uint32_t clients;          /* connected clients past the handshake, this one included */
	uint64_t underruns;        /* volumes that missed their revolution */
	uint64_t volumes_rendered; /* volumes rendered */
	uint64_t volumes_skipped;  /* scenes not rendered: identical to the last rendered */
	uint64_t bytes_uploaded;   /* bytes sent to the projector: whole volumes, or
				    * deltas of only the tiles that changed */
	uint32_t render_us;        /* wall time of the last render, microseconds (0: none yet) */
	float jitter_us;           /* RMS deviation of recent revolution periods */
	uint64_t missed_pulses;    /* index pulses missing or rejected as glitches */
	uint64_t upload_rate;      /* bytes/s sent to the projector, last second */
	float index_error_us;      /* RMS error of the predicted revolution start */
	float angle_error_p99;     /* slice angle error, 99th percentile, in slices
				    * (< 0: unknown; only the simulated projector knows) */
	float angle_error_max;     /* largest slice angle error, slices (< 0: unknown) */
	/* The daemon's limits (spindled(8)) and what they did since it
	 * started; from a daemon speaking protocol 3, else limits_known is
	 * false and they are 0. */
	bool limits_known;
	struct spindle_limits {
		uint64_t refused_clients;    /* connections over max-clients */
		uint64_t refused_per_user;   /* over max-clients-per-user */
		uint64_t refused_incomplete; /* over max-incomplete-clients */
		uint64_t handshake_timeouts; /* closed for no hello in time */
		uint64_t accept_pauses;      /* accepting paused, out of fds */
		uint32_t clients_in_handshake;
		uint32_t fds, fd_limit;              /* the daemon's open fds, RLIMIT_NOFILE */
		uint64_t memory_used, memory_budget; /* buffers + 16 bytes a vertex held, memory-budget */
		uint64_t refused_memory;             /* clients refused over memory-budget */
		uint32_t mappings, mapping_budget;   /* memfd buffers mapped, max-mappings */
		uint64_t refused_mappings;           /* clients refused over max-mappings */
	} limits;
	/* The daemon's safeguards as a service: systemd's watchdog, fed only
	 * while it makes progress, and max-client-fds; from a daemon
	 * speaking protocol 4 (when composition_known). */
	struct spindle_service {
		uint32_t watchdog_ms; /* WatchdogSec; 0: none asked for */
		uint64_t watchdog_fed, watchdog_withheld;
		uint32_t max_client_fds;
		uint64_t refused_fds; /* clients disconnected over it */
	} service;
	/* What the object cache and compositor did (spindled(8), key cache);
	 * from a daemon speaking protocol 4, else composition_known is false
	 * and they are 0. */
	bool composition_known;
	struct spindle_composition {
		bool cache;               /* on; off: the rest is 0 */
		uint32_t objects, cached; /* layers followed; of them, holding a cached volume */
		uint64_t cache_bytes, cache_budget;
		uint64_t hits, misses;           /* objects composed from the cache / rendered, over all volumes */
		uint64_t creates, invalidations; /* volumes cached; dropped for a change */
		uint64_t evictions;              /* dropped over cache-budget */
		uint32_t objects_rendered, objects_reused; /* the last volume */
		uint32_t render_us, compose_us;            /* the last volume: rendering objects, composing */
	} composition;
};

/* The display's state, pushed by the daemon when it changes (protocol
 * version 2): a flag changed, or the speed moved by 1% of nominal. */
struct spindle_state {
	bool locked;
	bool blanked;
	bool projector_present;
	float rpm; /* measured, 0 when not turning */
};

/* Why the daemon refused a commit (protocol version 2), or a calibration
 * (version 6). A refused commit shows nothing: every change stays pending,
 * frame requests too. */
enum spindle_refusal {
	SPINDLE_REFUSED_QUOTA = 1,        /* more primitives than this client's quota */
	SPINDLE_REFUSED_DENIED = 2,       /* exclusive layer, or calibration, not allowed */
	SPINDLE_REFUSED_BUSY = 3,         /* another client's exclusive layer shows */
	SPINDLE_REFUSED_OUT_OF_RANGE = 4, /* a calibration value out of its range */
};

/* Asynchronous events, called from spindle_dispatch() (and from the
 * blocking calls, which dispatch while they wait). Either may be NULL. */
struct spindle_listener {
	void (*state)(void *data, const struct spindle_state *state);
	/* object: the layer at fault, or 1 for the display. */
	void (*refused)(void *data, enum spindle_refusal code, uint32_t object, const char *message);
};

/* When a committed state was first shown. A commit that leaves the scene
 * as the last volume rendered shows it is not rendered again: its frame
 * names that volume, at the first revolution start after the commit. */
struct spindle_frame {
	uint64_t volume_seq; /* sequence number of the volume showing it */
	uint64_t time_ns;    /* CLOCK_MONOTONIC revolution start it is shown from,
			      * never earlier than the commit */
};

/* Connects to the daemon at path; NULL path means $SPINDLE_SOCKET, else
 * SPINDLE_DEFAULT_SOCKET. Performs the version handshake and waits for the
 * device info. Returns NULL with errno set on failure (EPROTO: the daemon
 * speaks no common version). The caller owns the result. */
struct spindle *spindle_connect(const char *path);
/* The same, offering at most protocol version max_version (1 ..
 * SPINDLE_PROTOCOL_VERSION): for testing how older clients are served. */
struct spindle *spindle_connect_version(const char *path, uint32_t max_version);

/* Closes the connection and frees every object made with it. Accepts NULL. */
void spindle_disconnect(struct spindle *sp);

/* Log handler for diagnostics (the library is silent without one). */
typedef void (*spindle_log_func)(void *data, const char *message);
void spindle_set_log_handler(struct spindle *sp, spindle_log_func func, void *data);

/* The negotiated protocol version. */
uint32_t spindle_get_version(struct spindle *sp);

/* Installs the listener for state and refused events (NULL: none). The
 * structure must outlive the connection or the next call. */
void spindle_set_listener(struct spindle *sp, const struct spindle_listener *listener, void *data);

/* The last state the daemon pushed (version 2; -ENOTSUP at version 1). */
int spindle_get_state(struct spindle *sp, struct spindle_state *out);

/* Device info; the pointer stays valid until spindle_disconnect(). */
const struct spindle_device_info *spindle_get_device_info(struct spindle *sp);

/* For event loops: the socket fd (owned by the library), to poll for
 * POLLIN; spindle_dispatch() reads and handles whatever events are
 * available without blocking (returns events handled, or -errno);
 * spindle_flush() writes queued requests (0, -EAGAIN if the socket is full:
 * poll for POLLOUT and call again, or -errno). */
int spindle_get_fd(struct spindle *sp);
int spindle_dispatch(struct spindle *sp);
int spindle_flush(struct spindle *sp);

/* Blocks until the daemon has handled every request sent so far, handling
 * events on the way. 0 or -errno. */
int spindle_roundtrip(struct spindle *sp);

/* Why the connection failed: the daemon's error message, or a local one;
 * NULL while it is healthy. Owned by the library. */
const char *spindle_get_error(struct spindle *sp);
/* The code of the daemon's fatal error (enum spindle_error_code,
 * docs/protocol.md, display.error), 0 while healthy or when the failure
 * was local. */
uint32_t spindle_get_error_code(struct spindle *sp);

/* The version of the libspindle the program runs with ("MAJOR.MINOR.MICRO"),
 * which may be newer than the SPINDLE_VERSION it was built against. */
const char *spindle_library_version(void);

/* A buffer of vertex or index data: a copy of size bytes from data, sent
 * inline when it is small (at most SPINDLE_INLINE_MAX bytes, protocol
 * version 2), else in a sealed memfd passed to the daemon. The caller owns
 * the result; destroy it when it is no longer drawn from (lists keep their
 * own copy of what they drew from it). */
struct spindle_buffer *spindle_buffer_create(struct spindle *sp, const void *data, size_t size);
/* Always inline (version 2; EINVAL over SPINDLE_INLINE_MAX). */
struct spindle_buffer *spindle_buffer_create_inline(struct spindle *sp, const void *data, size_t size);
/* Zero copy: the caller's memfd of at least size bytes, sealed at least
 * against shrinking (F_SEAL_SHRINK), is passed as it is. The caller keeps
 * fd; writes to it after a draw change nothing already drawn. */
struct spindle_buffer *spindle_buffer_create_from_fd(struct spindle *sp, int fd, uint64_t size);
void spindle_buffer_destroy(struct spindle_buffer *buf);

/* A display list: a retained command stream. Commands append; clear
 * empties it. Changes show at the next spindle_commit(). */
struct spindle_list *spindle_list_create(struct spindle *sp);
void spindle_list_destroy(struct spindle_list *list);
int spindle_list_clear(struct spindle_list *list);
/* Colour of the primitives that follow (default opaque white). Emissive:
 * alpha scales intensity. */
int spindle_list_set_color(struct spindle_list *list, uint8_t r, uint8_t g, uint8_t b, uint8_t a);
/* Transform of the primitives that follow: a column-major 4x4 affine
 * matrix (model -> layer space); default identity. */
int spindle_list_set_transform(struct spindle_list *list, const float m[16]);
/* Draws count vertices from buf starting at byte offset, each stride
 * bytes apart (0 = tightly packed, 12): count points, count/2 line
 * segments, count/3 triangles. */
int spindle_list_points(struct spindle_list *list, struct spindle_buffer *buf, size_t offset, uint32_t count,
			uint32_t stride);
int spindle_list_lines(struct spindle_list *list, struct spindle_buffer *buf, size_t offset, uint32_t count,
		       uint32_t stride);
int spindle_list_triangles(struct spindle_list *list, struct spindle_buffer *buf, size_t offset, uint32_t count,
			   uint32_t stride);

/* Primitive modes of spindle_list_draw() and spindle_list_draw_indexed(). */
enum spindle_mode {
	SPINDLE_POINTS = 0,
	SPINDLE_LINES = 1,
	SPINDLE_TRIANGLES = 2,
	SPINDLE_LINE_STRIP = 3, /* version 2: count - 1 segments */
};

/* Vertex layouts (version 2; spindle_list_set_vertex_format()). */
enum spindle_vertex_format {
	SPINDLE_XYZ = 0,            /* 3 float32, 12 bytes */
	SPINDLE_XYZ_RGBA8 = 1,      /* 3 float32, then R, G, B, A bytes: 16 bytes */
	SPINDLE_XYZ_RGBA_FLOAT = 2, /* 3 float32, then 4 float32 in 0..1: 28 bytes */
};

enum spindle_index_type {
	SPINDLE_INDEX_U16 = 2,
	SPINDLE_INDEX_U32 = 4,
};

/* Any mode; stride 0 = the vertex format's size. */
int spindle_list_draw(struct spindle_list *list, enum spindle_mode mode, struct spindle_buffer *buf, size_t offset,
		      uint32_t count, uint32_t stride);
/* Version 2: index_count vertices picked by the indices (each below
 * vertex_count) at index_offset of indices, from the vertices at offset
 * of vertices, stride bytes apart. */
int spindle_list_draw_indexed(struct spindle_list *list, enum spindle_mode mode, struct spindle_buffer *vertices,
			      size_t offset, uint32_t vertex_count, uint32_t stride, struct spindle_buffer *indices,
			      size_t index_offset, uint32_t index_count, enum spindle_index_type index_type);
/* Version 2: layout of the vertices of the draws that follow. With a
 * colour per vertex, set_color does not apply; colours are interpolated
 * along lines and across triangles (in steps of at most 16 of 255). */
int spindle_list_set_vertex_format(struct spindle_list *list, enum spindle_vertex_format format);
/* Version 2: size of the points that follow, 1 to 16 pixels square. */
int spindle_list_set_point_size(struct spindle_list *list, uint32_t size);
/* Version 2: saves / restores the transform, colour, point size and
 * vertex format (16 deep); multiply_transform post-multiplies the current
 * transform (m applies to the model first). */
int spindle_list_push(struct spindle_list *list);
int spindle_list_pop(struct spindle_list *list);
int spindle_list_multiply_transform(struct spindle_list *list, const float m[16]);

/* A layer: shows a list in the shared volume. New layers are visible, with
 * no list and the identity transform. */
struct spindle_layer *spindle_layer_create(struct spindle *sp);
void spindle_layer_destroy(struct spindle_layer *layer);
/* NULL list shows nothing. */
int spindle_layer_set_list(struct spindle_layer *layer, struct spindle_list *list);
int spindle_layer_set_transform(struct spindle_layer *layer, const float m[16]);
int spindle_layer_set_visible(struct spindle_layer *layer, bool visible);
/* Version 2: -1000 .. 1000 (default 0). When the scene holds more than the
 * daemon's max-scene-primitives, the lowest-priority layers are left out,
 * whole. */
int spindle_layer_set_priority(struct spindle_layer *layer, int32_t priority);
/* Version 2: while visible, show this client's layers alone. Granted at
 * commit by the daemon's policy; a refused commit is reported through the
 * listener (or spindle_commit_and_wait()'s result). */
int spindle_layer_set_exclusive(struct spindle_layer *layer, bool exclusive);

/* Frame callback: func is called (from spindle_dispatch()) once the state
 * of the next commit is first shown. Call before spindle_commit(). */
typedef void (*spindle_frame_func)(void *data, const struct spindle_frame *frame);
int spindle_request_frame(struct spindle *sp, spindle_frame_func func, void *data);

/* Makes everything set since the last commit show together. Queues the
 * request and flushes. 0 or -errno. */
int spindle_commit(struct spindle *sp);

/* Blocking helper: requests a frame, commits, and waits until it is shown.
 * frame (may be NULL) receives when. 0 or -errno; a refused commit
 * returns -EDQUOT (quota), -EACCES (exclusive denied) or -EBUSY (another
 * client's exclusive layer), with everything still pending. */
int spindle_commit_and_wait(struct spindle *sp, struct spindle_frame *frame);

/* Blocking: the daemon's current status. 0 or -errno. */
int spindle_get_status(struct spindle *sp, struct spindle_status *out);

/* Blocking: the next volume shown, as an .svol file in a memfd. On success
 * *fd (owned by the caller, positioned at 0) holds *size bytes. Capture is
 * restricted by the daemon (root, the daemon's own user, the admin group):
 * -EACCES otherwise. 0 or -errno. */
int spindle_capture(struct spindle *sp, int *fd, size_t *size);

/* ---- watchers (protocol 5) ---- */

/* A watcher: the volumes shown, live, as the daemon shows them, each one
 * sent sparse (the watch volume layout, docs/formats.md; common/wvol.h
 * decodes it) at most max_rate_hz a second and at most the daemon's
 * max-watch-rate, and only after the previous one was released: volumes
 * shown meanwhile are skipped, never queued. Restricted like capture. */
struct spindle_watcher;

struct spindle_watch_volume {
	const void *data; /* the watch volume, mapped read-only: size bytes */
	size_t size;
	int fd;           /* its sealed memfd; data and fd are the library's,
			   * valid until spindle_watch_release() */
	uint64_t seq;     /* the volume's sequence number */
	uint64_t skipped; /* volumes shown since the last one that it skipped */
};

/* Called from spindle_dispatch() with each volume (then call
 * spindle_watch_release(), now or later, for the next), or with NULL when
 * the daemon ended the watcher (spindle_watch_get_error() tells why). */
typedef void (*spindle_watch_func)(void *data, struct spindle_watcher *w, const struct spindle_watch_volume *vol);

/* Asks for a watcher (max_rate_hz 0 to 1000; 0: the daemon's rate). NULL +
 * errno: EPROTONOSUPPORT from a daemon older than protocol 5. A watcher the
 * daemon refuses is ended later, from spindle_dispatch(). */
struct spindle_watcher *spindle_watch_create(struct spindle *sp, uint32_t max_rate_hz, spindle_watch_func func,
					     void *data);
/* Done with the volume received last: its data and fd go, and the daemon
 * may send the next. 0 or -errno. */
int spindle_watch_release(struct spindle_watcher *w);
/* 0 while the watcher lives; once the daemon ended it, -EACCES (not
 * allowed to watch), -EUSERS (max-watchers reached) or -EIO. */
int spindle_watch_get_error(const struct spindle_watcher *w);
/* Ends the watcher (and releases its volume). Accepts NULL. */
void spindle_watch_destroy(struct spindle_watcher *w);

/* What the daemon's watchers did (display.watchers). */
struct spindle_watch_stats {
	uint32_t watchers, max_watchers, max_rate_hz;
	uint64_t volumes_sent, volumes_skipped, bytes_sent, refused, denied;
};

/* Blocking: the daemon's watcher counters (one display.get_status round).
 * 0 or -errno; -EPROTONOSUPPORT from a daemon older than protocol 5. */
int spindle_get_watch_stats(struct spindle *sp, struct spindle_watch_stats *out);

/* Volumes (protocol 6; docs/volumes.md): a 3-D grid of samples, shown
 * by a list's draw_volume where the images' slice planes cross it. */
struct spindle_volume;

enum spindle_volume_type {
	SPINDLE_VOLUME_U8 = 1,
	SPINDLE_VOLUME_U16 = 2,
	SPINDLE_VOLUME_I16 = 3, /* Hounsfield units of a CT, for one */
	SPINDLE_VOLUME_F32 = 4,
	SPINDLE_VOLUME_RGBA8 = 5, /* each sample its own colour, alpha scaling it */
};

enum spindle_sampling {
	SPINDLE_NEAREST = 0,
	SPINDLE_TRILINEAR = 1,
};

/* A volume of size[0] x size[1] x size[2] samples of type from buf at
 * offset (x fastest, then y, then z; little-endian), sample (x, y, z)
 * centred at ((x + 0.5) spacing[0], ...) in model units, y its up axis.
 * The daemon copies them: buf may be destroyed at once. NULL + errno:
 * EPROTONOSUPPORT from a daemon older than protocol 6; sizes (1 to 4096,
 * at most 2^31 samples), spacing (finite, above 0) and the buffer's
 * length are checked by the daemon (a fatal error). */
struct spindle_volume *spindle_volume_create(struct spindle *sp, struct spindle_buffer *buf, uint64_t offset,
					     enum spindle_volume_type type, const uint32_t size[3],
					     const float spacing[3]);
/* A list drawing it shows nothing of it from the next volume on. */
void spindle_volume_destroy(struct spindle_volume *vol);
/* Draws vol with the list's transform and colour: a sample below
 * threshold (rgba8: alpha below it) lights nothing; else its value in the
 * window (centre, width > 0) scales the colour, or picks an entry of the
 * table set by spindle_list_set_volume_lut(). 0 or -errno
 * (-EPROTONOSUPPORT before protocol 6). */
int spindle_list_draw_volume(struct spindle_list *list, struct spindle_volume *vol, enum spindle_sampling sampling,
			     float threshold, float window_center, float window_width);
/* The lookup table of the draw_volume calls that follow: count (2 to 4096)
 * RGBA8 entries from buf at offset, copied now; count 0: the colour again. */
int spindle_list_set_volume_lut(struct spindle_list *list, struct spindle_buffer *buf, uint64_t offset, uint32_t count);

/* The display's calibration (protocol 6; spindled(8), docs/rendering.md
 * "Calibration"): where a real projector's images land against volume
 * space, corrected in the render geometry. */
enum spindle_calibration_key {
	SPINDLE_CALIBRATION_PHASE_OFFSET = 0,    /* degrees, -180 to 180 */
	SPINDLE_CALIBRATION_AXIS_OFFSET_U = 1,   /* whole pixels */
	SPINDLE_CALIBRATION_AXIS_OFFSET_V = 2,   /* whole pixels */
	SPINDLE_CALIBRATION_VERTICAL_SCALE = 3,  /* 0.5 to 2 */
	SPINDLE_CALIBRATION_VERTICAL_OFFSET = 4, /* volume units, -0.5 to 0.5 */
};

struct spindle_calibration {
	float phase_offset;                   /* degrees */
	int32_t axis_offset_u, axis_offset_v; /* pixels */
	float vertical_scale;                 /* heights drawn times this, */
	float vertical_offset;                /* then moved up by this */
};

/* Blocking: the calibration in use (one display.get_status round). 0 or
 * -errno; -EPROTONOSUPPORT from a daemon older than protocol 6. */
int spindle_get_calibration(struct spindle *sp, struct spindle_calibration *out);
/* Blocking: sets one calibration value from the next volume on; out (may
 * be NULL) gets the calibration in use afterwards. 0, -EACCES (only root
 * and the daemon's user may calibrate), -ERANGE (value out of its range),
 * -EPROTONOSUPPORT (daemon older than protocol 6), or -errno. The daemon's
 * config file is not written. */
int spindle_calibrate(struct spindle *sp, enum spindle_calibration_key key, float value,
		      struct spindle_calibration *out);

#ifdef __cplusplus
}
#endif

#endif
