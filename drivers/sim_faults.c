/* Fault descriptions for the simulated rotor and index pulse: the text
 * grammar of sim_faults_parse() (sim_rotor.h) and the motion part applied
 * to a rotor. Strict: a spec the daemon takes from its configuration must
 * mean exactly one thing, so anything unexpected is -EINVAL. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim_rotor.h"

#define ITEM_MAX 64

/* A plain decimal number at *s (digits, sign, point, exponent: no inf, nan
 * or hex); advances *s past it. */
static int parse_num(const char **s, double *out)
{
	static const char plain[] = "0123456789.+-eE";
	char *end;
	if (!**s || !strchr(plain, **s))
		return -EINVAL; /* strtod would skip spaces */
	errno = 0;
	*out = strtod(*s, &end);
	if (errno || end == *s || !isfinite(*out) || strspn(*s, plain) < (size_t)(end - *s))
		return -EINVAL;
	*s = end;
	return 0;
}

/* A number in [lo, hi] that ends the value. */
static int parse_whole(const char *s, double lo, double hi, double *out)
{
	if (parse_num(&s, out) < 0 || *s || !(*out >= lo && *out <= hi))
		return -EINVAL;
	return 0;
}

/* Optional "<sep>number" in [lo, hi]; *out keeps its default without it. */
static int parse_opt(const char **s, char sep, double lo, double hi, double *out)
{
	if (**s != sep)
		return 0;
	(*s)++;
	if (parse_num(s, out) < 0 || !(*out >= lo && *out <= hi))
		return -EINVAL;
	return 0;
}

/* T:RPM@D */
static int parse_speed(const char *s, struct sim_fault_event *ev)
{
	*ev = (struct sim_fault_event){ .kind = SIM_FAULT_SPEED };
	if (parse_num(&s, &ev->at) < 0 || ev->at < 0 || *s++ != ':')
		return -EINVAL;
	if (parse_num(&s, &ev->rpm) < 0 || !(ev->rpm >= 1.0 && ev->rpm <= 100000.0) || *s++ != '@')
		return -EINVAL;
	return parse_whole(s, 0.0, 1e6, &ev->dur);
}

/* T[+R] */
static int parse_unplug(const char *s, struct sim_fault_event *ev)
{
	*ev = (struct sim_fault_event){ .kind = SIM_FAULT_UNPLUG, .restart = -1.0 };
	if (parse_num(&s, &ev->at) < 0 || ev->at < 0)
		return -EINVAL;
	if (*s == '+' && parse_opt(&s, '+', 0.0, 1e6, &ev->restart) < 0)
		return -EINVAL;
	return *s ? -EINVAL : 0;
}

/* T[/D][+R[/S]] */
static int parse_stall(const char *s, struct sim_fault_event *ev)
{
	*ev = (struct sim_fault_event){ .kind = SIM_FAULT_STALL, .restart = -1.0, .spinup = 1.0 };
	if (parse_num(&s, &ev->at) < 0 || ev->at < 0 || parse_opt(&s, '/', 0.0, 1e6, &ev->dur) < 0)
		return -EINVAL;
	if (*s == '+') {
		ev->restart = 0.0; /* parse_opt fills it */
		if (parse_opt(&s, '+', 0.0, 1e6, &ev->restart) < 0 || parse_opt(&s, '/', 0.0, 1e6, &ev->spinup) < 0)
			return -EINVAL;
	}
	return *s ? -EINVAL : 0;
}

static int parse_drift(const char *s, double *out)
{
	static const char unit[] = "ppm/s";
	if (parse_num(&s, out) < 0 || strcmp(s, unit) || !(*out >= -10000.0 && *out <= 10000.0))
		return -EINVAL;
	return 0;
}

static int parse_seed(const char *s, uint64_t *out)
{
	char *end;
	if (!*s || strspn(s, "0123456789") != strlen(s))
		return -EINVAL;
	errno = 0;
	*out = strtoull(s, &end, 10);
	return errno || *end ? -EINVAL : 0;
}

/* One key=value item; seen is a bit per once-only key. */
static int parse_item(char *item, struct sim_faults *f, unsigned *seen)
{
	static const char *const once[] = { "jitter", "missed", "extra", "drift", "seed" };
	char *val = strchr(item, '=');
	if (!val)
		return -EINVAL;
	*val++ = '\0';
	for (unsigned i = 0; i < sizeof(once) / sizeof(once[0]); i++) {
		if (strcmp(item, once[i]))
			continue;
		if (*seen & (1u << i))
			return -EINVAL;
		*seen |= 1u << i;
	}
	if (!strcmp(item, "jitter"))
		return parse_whole(val, 0.0, 0.1, &f->jitter);
	if (!strcmp(item, "missed"))
		return parse_whole(val, 0.0, 1.0, &f->missed);
	if (!strcmp(item, "extra"))
		return parse_whole(val, 0.0, 1.0, &f->extra);
	if (!strcmp(item, "drift"))
		return parse_drift(val, &f->drift_ppm_s);
	if (!strcmp(item, "seed"))
		return parse_seed(val, &f->seed);
	if (f->nevents == SIM_FAULTS_MAX_EVENTS)
		return -EINVAL;
	struct sim_fault_event *ev = &f->events[f->nevents];
	int r = !strcmp(item, "speed")    ? parse_speed(val, ev)
		: !strcmp(item, "stall")  ? parse_stall(val, ev)
		: !strcmp(item, "unplug") ? parse_unplug(val, ev)
					  : -EINVAL;
	f->nevents += r == 0;
	return r;
}

int sim_faults_parse(const char *spec, struct sim_faults *out)
{
	memset(out, 0, sizeof(*out));
	if (!spec)
		return -EINVAL;
	if (!*spec || !strcmp(spec, "none"))
		return 0;
	unsigned seen = 0;
	const char *s = spec;
	for (;;) {
		size_t len = strcspn(s, ",");
		char item[ITEM_MAX];
		if (len == 0 || len >= sizeof(item))
			goto err;
		memcpy(item, s, len);
		item[len] = '\0';
		if (parse_item(item, out, &seen) < 0)
			goto err;
		if (!s[len])
			return 0;
		s += len + 1;
	}
err:
	memset(out, 0, sizeof(*out));
	return -EINVAL;
}

struct speed_step {
	double at, rpm, dur; /* s after creation, target, ramp s */
};

/* The speed steps of f's events, in time order (a stall and its restart
 * are two steps, which later events may fall between). */
static size_t speed_steps(const struct sim_faults *f, double nominal, struct speed_step *st)
{
	size_t n = 0;
	for (uint32_t i = 0; i < f->nevents && i < SIM_FAULTS_MAX_EVENTS; i++) {
		const struct sim_fault_event *ev = &f->events[i];
		if (ev->kind == SIM_FAULT_UNPLUG)
			continue; /* the projector's, not the rotor's */
		if (ev->kind == SIM_FAULT_SPEED) {
			st[n++] = (struct speed_step){ ev->at, ev->rpm, ev->dur };
			continue;
		}
		st[n++] = (struct speed_step){ ev->at, 0.0, ev->dur };
		if (ev->restart >= 0.0)
			st[n++] = (struct speed_step){ ev->at + ev->restart, nominal, ev->spinup };
	}
	for (size_t i = 1; i < n; i++) /* insertion sort, stable */
		for (size_t j = i; j > 0 && st[j].at < st[j - 1].at; j--) {
			struct speed_step tmp = st[j];
			st[j] = st[j - 1];
			st[j - 1] = tmp;
		}
	return n;
}

int sim_rotor_apply_faults(struct sim_rotor *r, const struct sim_faults *f)
{
	if (!f)
		return 0;
	struct speed_step st[2 * SIM_FAULTS_MAX_EVENTS];
	double nominal = 60e9 / (double)sim_rotor_period_ns(r);
	sim_rotor_set_drift(r, f->drift_ppm_s);
	size_t n = speed_steps(f, nominal, st);
	for (size_t i = 0; i < n; i++) {
		int64_t t = sim_rotor_start(r) + llround(st[i].at * 1e9);
		int e = sim_rotor_set_speed(r, t, st[i].rpm, llround(st[i].dur * 1e9));
		if (e < 0)
			return e;
	}
	return 0;
}
