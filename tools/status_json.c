/* `spindlectl status --json` (status_json.h). */
#include "status_json.h"

#include <math.h>

/* A JSON string: quotes, backslashes and control characters escaped. */
static void put_string(FILE *f, const char *s)
{
	fputc('"', f);
	for (; *s; s++) {
		unsigned char ch = (unsigned char)*s;
		if (ch == '"' || ch == '\\')
			fprintf(f, "\\%c", ch);
		else if (ch < 0x20)
			fprintf(f, "\\u%04x", ch);
		else
			fputc(ch, f);
	}
	fputc('"', f);
}

/* A number JSON can hold: non-finite floats become null. */
static void put_float(FILE *f, double v)
{
	if (isfinite(v))
		fprintf(f, "%.6g", v);
	else
		fputs("null", f);
}

#define U(name, v) fprintf(f, ", \"" name "\": %llu", (unsigned long long)(v))
#define B(name, v) fprintf(f, ", \"" name "\": %s", (v) ? "true" : "false")
#define F(name, v) (fputs(", \"" name "\": ", f), put_float(f, (v)))

static void put_device(FILE *f, const struct spindle_device_info *d)
{
	fputs("\"device\": {\"name\": ", f);
	put_string(f, d->name);
	U("width", d->width);
	U("height", d->height);
	U("images_per_rev", d->images_per_rev);
	B("mirrored", d->mirrored);
	F("half_height", d->half_height);
	F("rpm", d->rpm);
	fputc('}', f);
}

static void put_display(FILE *f, const struct spindle_status *st)
{
	fputs(", \"display\": {\"rpm\": ", f);
	put_float(f, st->rpm);
	B("locked", st->locked);
	B("blanked", st->blanked);
	B("projector_present", st->projector_present);
	F("jitter_us", st->jitter_us);
	F("index_error_us", st->index_error_us);
	U("missed_pulses", st->missed_pulses);
	F("angle_error_p99", st->angle_error_p99); /* < 0: unknown */
	F("angle_error_max", st->angle_error_max);
	U("volumes_shown", st->volumes_shown);
	U("underruns", st->underruns);
	U("volumes_rendered", st->volumes_rendered);
	U("volumes_skipped", st->volumes_skipped);
	U("bytes_uploaded", st->bytes_uploaded);
	U("upload_rate", st->upload_rate);
	U("render_us", st->render_us);
	U("clients", st->clients);
	fputc('}', f);
}

static void put_limits(FILE *f, const struct spindle_limits *l)
{
	fprintf(f, ", \"limits\": {\"clients_in_handshake\": %u", l->clients_in_handshake);
	U("refused_clients", l->refused_clients);
	U("refused_per_user", l->refused_per_user);
	U("refused_incomplete", l->refused_incomplete);
	U("handshake_timeouts", l->handshake_timeouts);
	U("fds", l->fds);
	U("fd_limit", l->fd_limit);
	U("accept_pauses", l->accept_pauses);
	U("memory_used", l->memory_used);
	U("memory_budget", l->memory_budget);
	U("refused_memory", l->refused_memory);
	U("mappings", l->mappings);
	U("mapping_budget", l->mapping_budget);
	U("refused_mappings", l->refused_mappings);
	fputc('}', f);
}

static void put_service(FILE *f, const struct spindle_service *s)
{
	fprintf(f, ", \"service\": {\"watchdog_ms\": %u", s->watchdog_ms);
	U("watchdog_fed", s->watchdog_fed);
	U("watchdog_withheld", s->watchdog_withheld);
	U("max_client_fds", s->max_client_fds);
	U("refused_fds", s->refused_fds);
	fputc('}', f);
}

static void put_composition(FILE *f, const struct spindle_composition *c)
{
	fprintf(f, ", \"composition\": {\"cache\": %s", c->cache ? "true" : "false");
	U("objects", c->objects);
	U("cached", c->cached);
	U("cache_bytes", c->cache_bytes);
	U("cache_budget", c->cache_budget);
	U("hits", c->hits);
	U("misses", c->misses);
	U("creates", c->creates);
	U("invalidations", c->invalidations);
	U("evictions", c->evictions);
	U("objects_rendered", c->objects_rendered);
	U("objects_reused", c->objects_reused);
	U("render_us", c->render_us);
	U("compose_us", c->compose_us);
	fputc('}', f);
}

static void put_watchers(FILE *f, const struct spindle_watch_stats *w)
{
	fprintf(f, ", \"watchers\": {\"watchers\": %u, \"max_watchers\": %u, \"max_rate_hz\": %u", w->watchers,
		w->max_watchers, w->max_rate_hz);
	fprintf(f, ", \"volumes_sent\": %llu, \"volumes_skipped\": %llu, \"bytes_sent\": %llu",
		(unsigned long long)w->volumes_sent, (unsigned long long)w->volumes_skipped,
		(unsigned long long)w->bytes_sent);
	fprintf(f, ", \"refused\": %llu, \"denied\": %llu}", (unsigned long long)w->refused,
		(unsigned long long)w->denied);
}

static void put_calibration(FILE *f, const struct spindle_calibration *c)
{
	fprintf(f, ", \"calibration\": {\"phase_offset\": %.9g, \"axis_offset_u\": %d, \"axis_offset_v\": %d",
		(double)c->phase_offset, c->axis_offset_u, c->axis_offset_v);
	fprintf(f, ", \"vertical_scale\": %.9g, \"vertical_offset\": %.9g}", (double)c->vertical_scale,
		(double)c->vertical_offset);
}

void status_print_json(FILE *f, const char *socket, uint32_t protocol, const struct spindle_device_info *dev,
		       const struct spindle_status *st, const struct spindle_watch_stats *ws,
		       const struct spindle_calibration *cal)
{
	fputs("{\"socket\": ", f);
	put_string(f, socket);
	fprintf(f, ", \"protocol\": %u, ", protocol);
	put_device(f, dev);
	put_display(f, st);
	if (st->limits_known)
		put_limits(f, &st->limits); /* protocol 3 */
	if (st->composition_known) {        /* protocol 4 */
		put_service(f, &st->service);
		put_composition(f, &st->composition);
	}
	if (ws)
		put_watchers(f, ws); /* protocol 5 */
	if (cal)
		put_calibration(f, cal); /* protocol 6 */
	fputs("}\n", f);
}
