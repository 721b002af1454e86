/* The display's calibration (protocol 6): display.calibrate and the
 * calibration event. */
#include <errno.h>

#include "private.h"

int spindle_get_calibration(struct spindle *sp, struct spindle_calibration *out)
{
	if (!sp->dead && sp->version < 6)
		return -EPROTONOSUPPORT;
	struct spindle_status st;
	int r = spindle_get_status(sp, &st);
	if (r == 0)
		*out = sp->calibration;
	return r;
}

static bool calibration_arrived(struct spindle *sp, void *data)
{
	return sp->calibration_serial != *(uint64_t *)data;
}

int spindle_calibrate(struct spindle *sp, enum spindle_calibration_key key, float value,
		      struct spindle_calibration *out)
{
	if (sp->dead)
		return -EPIPE;
	if (sp->version < 6)
		return -EPROTONOSUPPORT;
	uint64_t serial = sp->calibration_serial;
	int r = lib_sent(sp, proto_req_display_calibrate(sp->conn, 1, (uint32_t)key, value));
	/* The daemon answers with calibration, after refused when it refused. */
	if (r == 0)
		r = lib_wait(sp, calibration_arrived, &serial);
	if (r < 0)
		return r;
	if (out)
		*out = sp->calibration;
	if (sp->calibration_refusal)
		return sp->calibration_refusal == PROTO_DISPLAY_REFUSAL_DENIED ? -EACCES : -ERANGE;
	return 0;
}
