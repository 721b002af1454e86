/* spindled's configuration: built-in defaults, then the config file, then
 * the command line (docs/man/spindled.8 lists every key). */
#ifndef SPINDLE_CONFIG_H
#define SPINDLE_CONFIG_H

#include <stdbool.h>
#include <stdint.h>

#include "calibration.h"

#define CONFIG_DEFAULT_PATH "/etc/spindle/spindled.conf"

/* Who a privilege is granted to: nobody, root + the daemon's user + the
 * admin group, or every client. */
enum policy {
	POLICY_NONE,
	POLICY_ADMIN,
	POLICY_ANY,
};

const char *config_policy_name(enum policy p);

struct config {
	char socket_path[108];           /* sun_path size */
	char device[16];                 /* "sim" or "hw" */
	char profile[32];                /* "perspecta", "small" */
	char renderer[16];               /* "auto", "cpu", "egl", "osmesa" */
	unsigned render_threads;         /* 0 = one per core */
	unsigned projector_buffers;      /* 2 or 3 */
	uint64_t sim_link_bytes_per_sec; /* 0 = unlimited */
	char sim_faults[256];            /* simulated rotor faults (sim_faults_parse()), "" = none */
	/* device = hw: the index pulse's GPIO line and the USB projector. */
	char sync_chip[64]; /* "gpiochip0", "/dev/gpiochip0", a label or a number */
	char sync_line[64]; /* offset or line name */
	bool sync_active_low;
	uint16_t projector_vid, projector_pid; /* 0 = any Spindle projector */
	char projector_path[32];               /* USB bus path "1-2.4", "" = any */
	bool blank_only;                       /* --blank: darken the projector and exit */
	uint64_t memory_budget;                /* all clients: buffer bytes + CLIENT_VERTEX_BYTES per vertex held */
	uint32_t max_mappings;                 /* all clients: memfd buffers mapped */
	uint32_t max_clients;                  /* one kept for an admin (admission.h) */
	uint32_t admin_reserved_clients;       /* of max_clients, kept for admins */
	uint32_t max_clients_per_user;         /* connections of one non-admin uid */
	uint32_t max_incomplete_clients;       /* non-admin connections before hello */
	uint32_t handshake_timeout_ms;         /* no hello by then: closed */
	uint32_t max_client_fds;               /* received fds one client may hold ahead of their messages */
	uint32_t max_objects;                  /* per client */
	uint64_t max_buffer_bytes;             /* per client */
	uint64_t max_vertices;                 /* per client */
	uint64_t max_primitives;               /* per client, per volume */
	uint64_t max_scene_primitives;         /* all clients, per volume: priority decides */
	uint32_t max_watchers;                 /* all clients: watchers (display.watch) */
	uint32_t max_watch_rate;               /* Hz: at most this many volumes a second per watcher */
	bool cache;                            /* the object cache and compositor (cache.h) */
	bool half_turn_swaps;                  /* swap at half-turn starts where the projector can */
	uint8_t brightness;                    /* enum geometry_brightness (geometry.h) */
	struct calibration calibration;        /* calibration.h: changed live by display.calibrate */
	uint64_t cache_budget;                 /* bytes it may hold */
	enum policy exclusive;                 /* who may have exclusive layers */
	char admin_group[32];                  /* may capture, and be exclusive under "admin" */
	char user[32]; /* started as root: run as this user after opening the devices ("root": stay root) */
	bool verbose;
};

void config_defaults(struct config *cfg);

/* Sets one key ("profile", "max-objects", ...) from text. 0, or -EINVAL
 * (bad value) or -ENOENT (unknown key). */
int config_set(struct config *cfg, const char *key, const char *value);
/* The values a key with a fixed set of them takes ("auto, cpu, ..."), for
 * messages; NULL for other keys. */
const char *config_key_values(const char *key);

/* Reads "key = value" lines ('#' comments). A missing file is fine when
 * required is false. 0 or negative errno; errors are logged with the line. */
int config_load(struct config *cfg, const char *path, bool required);

#endif
