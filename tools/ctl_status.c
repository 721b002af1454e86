/* spindlectl status and calibrate: the daemon's state, and its
 * calibration shown, set live and saved (spindlectl(1)). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>

#include "calibration.h"
#include "config_edit.h"
#include "ctl.h"
#include "status_json.h"

/* ---- status ---- */

static void print_device(const struct spindle_device_info *info)
{
	printf("device: %s\n", info->name);
	printf("width: %u\n", info->width);
	printf("height: %u\n", info->height);
	printf("images per revolution: %u\n", info->images_per_rev);
	printf("mirrored: %s\n", info->mirrored ? "yes" : "no");
	printf("half height: %g\n", info->half_height);
	printf("nominal rpm: %g\n", info->rpm);
}

static void print_status(const struct spindle_status *st)
{
	printf("measured rpm: %.1f\n", st->rpm);
	printf("locked: %s\n", st->locked ? "yes" : "no");
	printf("period jitter: %.1f us\n", st->jitter_us);
	printf("index prediction error: %.1f us\n", st->index_error_us);
	printf("missed or glitch pulses: %llu\n", (unsigned long long)st->missed_pulses);
	if (st->angle_error_p99 >= 0)
		printf("slice angle error: p99 %.3f, max %.3f slices\n", st->angle_error_p99, st->angle_error_max);
	else
		printf("slice angle error: unknown\n");
	printf("blanked: %s\n", st->blanked ? "yes" : "no");
	printf("projector present: %s\n", st->projector_present ? "yes" : "no");
	printf("volumes shown: %llu\n", (unsigned long long)st->volumes_shown);
	printf("underruns: %llu\n", (unsigned long long)st->underruns);
	printf("volumes rendered: %llu\n", (unsigned long long)st->volumes_rendered);
	printf("volumes skipped: %llu\n", (unsigned long long)st->volumes_skipped);
	printf("bytes uploaded: %llu\n", (unsigned long long)st->bytes_uploaded);
	printf("upload rate: %llu bytes/s\n", (unsigned long long)st->upload_rate);
	printf("render time: %.3f ms\n", st->render_us / 1e3);
	printf("clients: %u\n", st->clients);
}

static void print_limits(const struct spindle_limits *l)
{
	printf("clients in handshake: %u\n", l->clients_in_handshake);
	printf("refused clients: %llu over max-clients, %llu over max-clients-per-user, %llu over "
	       "max-incomplete-clients\n",
	       (unsigned long long)l->refused_clients, (unsigned long long)l->refused_per_user,
	       (unsigned long long)l->refused_incomplete);
	printf("handshake timeouts: %llu\n", (unsigned long long)l->handshake_timeouts);
	printf("file descriptors: %u of %u; accepting paused %llu times\n", l->fds, l->fd_limit,
	       (unsigned long long)l->accept_pauses);
	printf("memory: %llu of %llu bytes; %llu clients refused over it\n", (unsigned long long)l->memory_used,
	       (unsigned long long)l->memory_budget, (unsigned long long)l->refused_memory);
	printf("mappings: %u of %u; %llu clients refused over it\n", l->mappings, l->mapping_budget,
	       (unsigned long long)l->refused_mappings);
}

static void print_service(const struct spindle_service *s)
{
	printf("client fds: at most %u each; %llu clients disconnected over it\n", s->max_client_fds,
	       (unsigned long long)s->refused_fds);
	if (s->watchdog_ms)
		printf("watchdog: %u ms, fed %llu times, withheld %llu times\n", s->watchdog_ms,
		       (unsigned long long)s->watchdog_fed, (unsigned long long)s->watchdog_withheld);
	else
		printf("watchdog: none\n");
}

static void print_composition(const struct spindle_composition *c)
{
	if (!c->cache) {
		printf("object cache: off\n");
		return;
	}
	printf("object cache: %u objects, %u cached, %llu of %llu bytes\n", c->objects, c->cached,
	       (unsigned long long)c->cache_bytes, (unsigned long long)c->cache_budget);
	printf("cache hits: %llu, misses: %llu, volumes cached: %llu, invalidated: %llu, evicted: %llu\n",
	       (unsigned long long)c->hits, (unsigned long long)c->misses, (unsigned long long)c->creates,
	       (unsigned long long)c->invalidations, (unsigned long long)c->evictions);
	printf("last volume: %u objects rendered in %.3f ms, %u reused, composed in %.3f ms\n", c->objects_rendered,
	       c->render_us / 1e3, c->objects_reused, c->compose_us / 1e3);
}

static void print_calibration(const struct spindle_calibration *c)
{
	printf("calibration: phase-offset %g deg, axis-offset-u %d px, axis-offset-v %d px, vertical-scale %g, "
	       "vertical-offset %g\n",
	       (double)c->phase_offset, c->axis_offset_u, c->axis_offset_v, (double)c->vertical_scale,
	       (double)c->vertical_offset);
}

/* What status reports: the daemon's status, and its watchers' and
 * calibration where its protocol has them. */
struct status_all {
	struct spindle_status st;
	struct spindle_watch_stats ws;
	struct spindle_calibration cal;
	bool watch_known, cal_known;
};

static int fetch_status(struct spindle *sp, struct status_all *s)
{
	int ret = spindle_get_status(sp, &s->st);
	if (ret == 0 && spindle_get_version(sp) >= 5) { /* protocol 5 */
		ret = spindle_get_watch_stats(sp, &s->ws);
		s->watch_known = ret == 0;
	}
	if (ret == 0 && spindle_get_version(sp) >= 6) { /* protocol 6 */
		ret = spindle_get_calibration(sp, &s->cal);
		s->cal_known = ret == 0;
	}
	return ret;
}

static void print_watchers(const struct spindle_watch_stats *ws)
{
	printf("watchers: %u of %u (at most %u/s each), %llu volumes sent (%llu bytes), %llu skipped, %llu refused, "
	       "%llu denied\n",
	       ws->watchers, ws->max_watchers, ws->max_rate_hz, (unsigned long long)ws->volumes_sent,
	       (unsigned long long)ws->bytes_sent, (unsigned long long)ws->volumes_skipped,
	       (unsigned long long)ws->refused, (unsigned long long)ws->denied);
}

int cmd_status(const struct ctl_args *a)
{
	struct spindle *sp = ctl_connect(a);
	if (!sp)
		return CTL_CONNECT;
	struct status_all s = { .watch_known = false };
	int ret = fetch_status(sp, &s);
	if (ret < 0) {
		ctl_report_failure(sp, "status", ret);
		spindle_disconnect(sp);
		return CTL_FAILED;
	}
	if (a->json) {
		status_print_json(stdout, ctl_socket_path(a), spindle_get_version(sp), spindle_get_device_info(sp),
				  &s.st, s.watch_known ? &s.ws : NULL, s.cal_known ? &s.cal : NULL);
		spindle_disconnect(sp);
		return fflush(stdout) == 0 ? CTL_OK : CTL_FAILED;
	}
	printf("socket: %s\n", ctl_socket_path(a));
	printf("protocol version: %u\n", spindle_get_version(sp));
	print_device(spindle_get_device_info(sp));
	print_status(&s.st);
	if (s.st.limits_known) /* protocol 3 */
		print_limits(&s.st.limits);
	if (s.st.composition_known) { /* protocol 4 */
		print_service(&s.st.service);
		print_composition(&s.st.composition);
	}
	if (s.watch_known)
		print_watchers(&s.ws);
	if (s.cal_known)
		print_calibration(&s.cal);
	spindle_disconnect(sp);
	return fflush(stdout) == 0 ? CTL_OK : CTL_FAILED;
}

/* ---- calibrate ---- */

#define CONFIG_PATH "/etc/spindle/spindled.conf"

/* Checks KEY VALUE here first, for a usage error rather than a refusal. */
static int parse_calibration(const struct ctl_args *a, int *key, struct calibration *cal)
{
	calibration_identity(cal);
	*key = calibration_key_from_name(a->operand[0]);
	if (*key < 0)
		return ctl_usage_error("unknown calibration key '%s' (phase-offset, axis-offset-u, axis-offset-v, "
				       "vertical-scale, vertical-offset)",
				       a->operand[0]);
	if (calibration_set_text(cal, (unsigned)*key, a->operand[1]) < 0)
		return ctl_usage_error("bad value '%s' (phase-offset: -180..180 degrees; axis offsets: whole pixels; "
				       "vertical-scale: 0.5..2; vertical-offset: -0.5..0.5)",
				       a->operand[1]);
	return -1;
}

/* The value set, into the config file the daemon reads at start. */
static int save_calibration(const struct ctl_args *a, const struct calibration *cal, int key)
{
	char value[32], err[600];
	calibration_format(cal, (unsigned)key, value, sizeof(value));
	const char *path = a->config ? a->config : CONFIG_PATH;
	if (config_edit_set(path, calibration_key_name((unsigned)key), value, err, sizeof(err)) < 0) {
		fprintf(stderr, "spindlectl: --save: %s\n", err);
		return CTL_FAILED;
	}
	printf("saved %s = %s in %s\n", calibration_key_name((unsigned)key), value, path);
	return CTL_OK;
}

int cmd_calibrate(const struct ctl_args *a)
{
	int key = -1, status;
	struct calibration want;
	if (a->operand_count == 2 && (status = parse_calibration(a, &key, &want)) >= 0)
		return status;
	if (a->operand_count == 0 && (a->save || a->config))
		return ctl_usage_error("%s", "--save and --config go with 'calibrate KEY VALUE'");
	if (a->config && !a->save)
		return ctl_usage_error("%s", "--config goes with --save");
	struct spindle *sp = ctl_connect(a);
	if (!sp)
		return CTL_CONNECT;
	struct spindle_calibration cal;
	int r = key < 0 ? spindle_get_calibration(sp, &cal)
			: spindle_calibrate(sp, (enum spindle_calibration_key)key,
					    (float)calibration_get(&want, (unsigned)key), &cal);
	status = CTL_OK;
	if (r == -EPROTONOSUPPORT) {
		fprintf(stderr, "spindlectl: calibrate: spindled speaks protocol %u; calibration needs 6\n",
			spindle_get_version(sp));
		status = CTL_FAILED;
	} else if (r == -EACCES || r == -ERANGE) {
		fprintf(stderr, "spindlectl: calibrate: refused: %s\n",
			r == -EACCES ? "only root and the daemon's user may calibrate"
				     : "value out of range for this display");
		status = CTL_REFUSED;
	} else if (r < 0) {
		ctl_report_failure(sp, "calibrate", r);
		status = CTL_FAILED;
	}
	spindle_disconnect(sp);
	if (status != CTL_OK)
		return status;
	print_calibration(&cal);
	if (a->save)
		status = save_calibration(a, &want, key);
	return fflush(stdout) == 0 ? status : CTL_FAILED;
}
