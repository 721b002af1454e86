#include "config.h"

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry.h"
#include "log.h"
#include "sim_rotor.h"
#include "wire.h"

void config_defaults(struct config *cfg)
{
	*cfg = (struct config){
		.render_threads = 0,
		.projector_buffers = 3,
		.sim_link_bytes_per_sec = 400u * 1000 * 1000, /* ~USB 3 sustained */
		.max_clients = 64,
		.memory_budget = 1ull << 30,
		.max_mappings = 16384,
		.admin_reserved_clients = 1,
		.max_clients_per_user = 16,
		.max_incomplete_clients = 16,
		.handshake_timeout_ms = 5000,
		.max_client_fds = PROTO_MAX_QUEUED_FDS,
		.max_watchers = 4,
		.max_watch_rate = 15,
		.max_objects = 4096,
		.max_buffer_bytes = 1ull << 30,
		.max_vertices = 32u << 20,
		.max_primitives = 8u << 20,
		.max_scene_primitives = 16u << 20,
		.cache = true,
		.half_turn_swaps = true,
		.brightness = GEOMETRY_BRIGHTNESS_EVEN,
		.cache_budget = 256ull << 20,
		.exclusive = POLICY_ADMIN,
	};
	calibration_identity(&cfg->calibration);
	strcpy(cfg->admin_group, "spindle-admin");
	const char *user = getenv("SPINDLE_USER");
	snprintf(cfg->user, sizeof(cfg->user), "%s", user && *user ? user : "spindle");
	const char *env = getenv("SPINDLE_SOCKET");
	snprintf(cfg->socket_path, sizeof(cfg->socket_path), "%s", env && *env ? env : "/run/spindle/spindle.sock");
	strcpy(cfg->device, "sim");
	strcpy(cfg->sync_chip, "gpiochip0");
	strcpy(cfg->sync_line, "ROTOR_INDEX");
	strcpy(cfg->profile, "perspecta");
	strcpy(cfg->renderer, "auto");
}

static int set_string(char *dst, size_t size, const char *value)
{
	if (!*value || strlen(value) >= size)
		return -EINVAL;
	strcpy(dst, value);
	return 0;
}

static int set_u64(uint64_t *dst, const char *value, uint64_t min, uint64_t max)
{
	char *end;
	errno = 0;
	unsigned long long v = strtoull(value, &end, 10);
	if (errno || end == value || *end || value[0] == '-' || v < min || v > max)
		return -EINVAL;
	*dst = v;
	return 0;
}

static int set_u32(uint32_t *dst, const char *value, uint32_t min, uint32_t max)
{
	uint64_t v;
	int r = set_u64(&v, value, min, max);
	if (r == 0)
		*dst = (uint32_t)v;
	return r;
}

/* May be empty ("" clears it). */
static int set_optional(char *dst, size_t size, const char *value)
{
	return *value ? set_string(dst, size, value) : (*dst = '\0', 0);
}

static const char *const policy_names[] = { "none", "admin", "any" };

const char *config_key_values(const char *key)
{
	static const struct {
		const char *key, *values;
	} keys[] = {
		{ "device", "sim, hw" },
		{ "profile", "perspecta, small" },
		{ "renderer", "auto, cpu, egl, osmesa" },
		{ "exclusive", "none, admin, any" },
		{ "brightness", "exact, even, uniform" },
	};
	for (size_t i = 0; i < sizeof(keys) / sizeof(keys[0]); i++)
		if (!strcmp(key, keys[i].key))
			return keys[i].values;
	return NULL;
}

const char *config_policy_name(enum policy p)
{
	return policy_names[p];
}

static int set_policy(enum policy *dst, const char *value)
{
	for (unsigned i = 0; i < sizeof(policy_names) / sizeof(policy_names[0]); i++)
		if (!strcmp(value, policy_names[i]))
			return *dst = (enum policy)i, 0;
	return -EINVAL;
}

static int set_bool(bool *dst, const char *value)
{
	if (!strcmp(value, "true") || !strcmp(value, "yes") || !strcmp(value, "1"))
		return *dst = true, 0;
	if (!strcmp(value, "false") || !strcmp(value, "no") || !strcmp(value, "0"))
		return *dst = false, 0;
	return -EINVAL;
}

/* A USB id: hexadecimal, "0x" optional (lsusb prints them bare). */
static int set_u16_hex(uint16_t *dst, const char *value)
{
	char *end;
	errno = 0;
	unsigned long v = strtoul(value, &end, 16);
	if (errno || end == value || *end || value[0] == '-' || v > 0xffff)
		return -EINVAL;
	*dst = (uint16_t)v;
	return 0;
}

static int config_set_hw(struct config *cfg, const char *key, const char *value);
static int config_set_limits(struct config *cfg, const char *key, const char *value);
static int config_set_scene_limits(struct config *cfg, const char *key, const char *value);

int config_set(struct config *cfg, const char *key, const char *value)
{
	if (!strcmp(key, "socket"))
		return set_string(cfg->socket_path, sizeof(cfg->socket_path), value);
	if (!strcmp(key, "device"))
		return strcmp(value, "sim") && strcmp(value, "hw")
			       ? -EINVAL
			       : set_string(cfg->device, sizeof(cfg->device), value);
	if (!strcmp(key, "profile")) {
		struct geometry g;
		return geometry_from_profile(value, &g) < 0 ? -EINVAL
							    : set_string(cfg->profile, sizeof(cfg->profile), value);
	}
	if (!strcmp(key, "renderer")) {
		/* Every name is accepted in every build: one without OSMesa
		 * (or a machine without EGL) falls back to the CPU renderer
		 * with a warning when it starts (server.c). */
		static const char *const names[] = { "auto", "cpu", "egl", "osmesa" };
		for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); i++)
			if (!strcmp(value, names[i]))
				return set_string(cfg->renderer, sizeof(cfg->renderer), value);
		return -EINVAL;
	}
	if (!strcmp(key, "brightness"))
		return geometry_brightness_parse(value, &cfg->brightness);
	int cal = calibration_key_from_name(key);
	if (cal >= 0)
		return calibration_set_text(&cfg->calibration, (unsigned)cal, value);
	if (!strcmp(key, "render-threads"))
		return set_u32(&cfg->render_threads, value, 0, 256);
	if (!strcmp(key, "projector-buffers"))
		return set_u32(&cfg->projector_buffers, value, 2, 3);
	if (!strcmp(key, "sim-link-rate"))
		return set_u64(&cfg->sim_link_bytes_per_sec, value, 0, UINT64_MAX);
	if (!strcmp(key, "sim-faults")) {
		struct sim_faults f;
		if (sim_faults_parse(value, &f) < 0)
			return -EINVAL;
		return set_optional(cfg->sim_faults, sizeof(cfg->sim_faults), value);
	}
	return config_set_hw(cfg, key, value);
}

/* The keys of device = hw. */
static int config_set_hw(struct config *cfg, const char *key, const char *value)
{
	if (!strcmp(key, "sync-chip"))
		return set_string(cfg->sync_chip, sizeof(cfg->sync_chip), value);
	if (!strcmp(key, "sync-line"))
		return set_string(cfg->sync_line, sizeof(cfg->sync_line), value);
	if (!strcmp(key, "sync-active-low"))
		return set_bool(&cfg->sync_active_low, value);
	if (!strcmp(key, "projector-vid"))
		return set_u16_hex(&cfg->projector_vid, value);
	if (!strcmp(key, "projector-pid"))
		return set_u16_hex(&cfg->projector_pid, value);
	if (!strcmp(key, "projector-path"))
		return set_optional(cfg->projector_path, sizeof(cfg->projector_path), value);
	return config_set_limits(cfg, key, value);
}

/* The user to run as, and the limits on clients. */
static int config_set_limits(struct config *cfg, const char *key, const char *value)
{
	if (!strcmp(key, "max-clients"))
		return set_u32(&cfg->max_clients, value, 1, 65536);
	if (!strcmp(key, "memory-budget"))
		return set_u64(&cfg->memory_budget, value, 1 << 20, UINT64_MAX / 2);
	if (!strcmp(key, "max-mappings"))
		return set_u32(&cfg->max_mappings, value, 1, 1u << 20);
	if (!strcmp(key, "user"))
		return set_string(cfg->user, sizeof(cfg->user), value);
	if (!strcmp(key, "admin-reserved-clients"))
		return set_u32(&cfg->admin_reserved_clients, value, 0, 65536);
	if (!strcmp(key, "max-clients-per-user"))
		return set_u32(&cfg->max_clients_per_user, value, 1, 65536);
	if (!strcmp(key, "max-incomplete-clients"))
		return set_u32(&cfg->max_incomplete_clients, value, 1, 65536);
	if (!strcmp(key, "handshake-timeout-ms"))
		return set_u32(&cfg->handshake_timeout_ms, value, 10, 600000);
	if (!strcmp(key, "max-client-fds"))
		return set_u32(&cfg->max_client_fds, value, PROTO_MAX_MESSAGE_FDS, PROTO_MAX_QUEUED_FDS);
	if (!strcmp(key, "max-watchers"))
		return set_u32(&cfg->max_watchers, value, 0, 1024);
	if (!strcmp(key, "max-watch-rate"))
		return set_u32(&cfg->max_watch_rate, value, 1, 1000);
	return config_set_scene_limits(cfg, key, value);
}

/* The limits on scenes, the cache, and who may have exclusive layers. */
static int config_set_scene_limits(struct config *cfg, const char *key, const char *value)
{
	if (!strcmp(key, "max-objects"))
		return set_u32(&cfg->max_objects, value, 1, 1u << 24);
	if (!strcmp(key, "max-buffer-bytes"))
		return set_u64(&cfg->max_buffer_bytes, value, 0, 1ull << 40);
	if (!strcmp(key, "max-vertices"))
		return set_u64(&cfg->max_vertices, value, 0, 1ull << 32);
	if (!strcmp(key, "max-primitives"))
		return set_u64(&cfg->max_primitives, value, 0, 1ull << 32);
	if (!strcmp(key, "max-scene-primitives"))
		return set_u64(&cfg->max_scene_primitives, value, 0, 1ull << 32);
	if (!strcmp(key, "cache"))
		return set_bool(&cfg->cache, value);
	if (!strcmp(key, "half-turn-swaps"))
		return set_bool(&cfg->half_turn_swaps, value);
	if (!strcmp(key, "cache-budget"))
		return set_u64(&cfg->cache_budget, value, 0, UINT64_MAX / 2);
	if (!strcmp(key, "exclusive"))
		return set_policy(&cfg->exclusive, value);
	if (!strcmp(key, "admin-group"))
		return set_optional(cfg->admin_group, sizeof(cfg->admin_group), value);
	return -ENOENT;
}

static char *trim(char *s)
{
	while (isspace((unsigned char)*s))
		s++;
	char *e = s + strlen(s);
	while (e > s && isspace((unsigned char)e[-1]))
		*--e = '\0';
	return s;
}

/* The longest line a config file may have, in bytes, not counting its "\n"
 * or "\r\n" ending (docs/man/spindled.8). A longer one is an error, not
 * read as two lines: its tail could pass for a key of its own. */
#define CONFIG_LINE_MAX 511

enum line_status {
	LINE_OK,
	LINE_EOF,
	LINE_TOO_LONG, /* the rest of it was read and dropped */
	LINE_NUL,
};

/* Reads one line of f into buf (CONFIG_LINE_MAX + 2 bytes: the line, a
 * '\r' before its '\n', the terminating NUL) without its line ending. The
 * last line may lack a '\n'. LINE_EOF at the end of the file, or on a read
 * error (ferror() tells). */
static enum line_status read_line(FILE *f, char *buf)
{
	size_t len = 0;
	bool nul = false, too_long = false;
	int c;
	while ((c = getc(f)) != EOF && c != '\n') {
		if (len < CONFIG_LINE_MAX + 1)
			buf[len++] = (char)c;
		else
			too_long = true;
		nul |= c == '\0';
	}
	if (c == EOF && (len == 0 || ferror(f)) && !too_long)
		return LINE_EOF;
	if (!too_long && len > 0 && buf[len - 1] == '\r')
		len--;
	buf[len] = '\0';
	if (too_long || len > CONFIG_LINE_MAX)
		return LINE_TOO_LONG;
	return nul ? LINE_NUL : LINE_OK;
}

/* One line n of path, without its ending: a comment, blank, or key =
 * value. 0 or -EINVAL (logged). */
static int parse_line(struct config *cfg, const char *path, unsigned n, char *line)
{
	char *hash = strchr(line, '#');
	if (hash)
		*hash = '\0';
	char *s = trim(line);
	if (!*s)
		return 0;
	char *eq = strchr(s, '=');
	if (!eq) {
		log_error("%s:%u: expected key = value", path, n);
		return -EINVAL;
	}
	*eq = '\0';
	char *key = trim(s), *value = trim(eq + 1);
	int e = config_set(cfg, key, value);
	if (e < 0) {
		const char *values = config_key_values(key);
		log_error("%s:%u: %s '%s'%s%s%s", path, n, e == -ENOENT ? "unknown key" : "bad value for", key,
			  values ? " (one of: " : "", values ? values : "", values ? ")" : "");
		return -EINVAL;
	}
	return 0;
}

int config_load(struct config *cfg, const char *path, bool required)
{
	FILE *f = fopen(path, "re");
	if (!f) {
		if (errno == ENOENT && !required)
			return 0;
		log_error("cannot read %s: %s", path, strerror(errno));
		return -errno;
	}
	char line[CONFIG_LINE_MAX + 2];
	int r = 0;
	enum line_status st;
	for (unsigned n = 1; (st = read_line(f, line)) != LINE_EOF; n++) {
		if (st == LINE_TOO_LONG) {
			log_error("%s:%u: longer than %d bytes", path, n, CONFIG_LINE_MAX);
			r = -EINVAL;
			continue;
		}
		if (st == LINE_NUL) {
			log_error("%s:%u: NUL byte", path, n);
			r = -EINVAL;
			continue;
		}
		if (parse_line(cfg, path, n, line) < 0)
			r = -EINVAL;
	}
	if (ferror(f)) {
		log_error("cannot read %s: %s", path, strerror(errno));
		r = -EIO;
	}
	fclose(f);
	return r;
}
