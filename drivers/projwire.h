/* The projector wire protocol (proto/projector.md, version 1.2): one codec for
 * both ends. The host side (the USB driver, the simulated projector's host
 * half) uses the encoders; the device side (the simulated projector's device
 * model, device firmware tests) uses the strict, incremental decoder and the
 * control request parser.
 *
 * Everything on the wire is little-endian. Encoders write into caller
 * buffers of the documented sizes and cannot fail; decoders validate every
 * field and return negative errno. */
#ifndef SPINDLE_PROJWIRE_H
#define SPINDLE_PROJWIRE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "geometry.h"
#include "volume.h"

#define PROJWIRE_VERSION_MAJOR 1
#define PROJWIRE_VERSION_MINOR 2 /* 1.1: delta volumes; 1.2: half-turn swaps */

/* USB interface descriptor of a Spindle projector. */
#define PROJWIRE_USB_CLASS 0xff
#define PROJWIRE_USB_SUBCLASS 0x53 /* 'S' */
#define PROJWIRE_USB_PROTOCOL 0x01

#define PROJWIRE_SETUP_SIZE 8
#define PROJWIRE_INFO_SIZE 64
#define PROJWIRE_STATUS_SIZE 64
#define PROJWIRE_TIMING_SIZE 24
#define PROJWIRE_CTRL_DATA_MAX 64

#define PROJWIRE_HEADER_SIZE 8
#define PROJWIRE_MAGIC0 0x53             /* 'S' */
#define PROJWIRE_MAGIC1 0x50             /* 'P' */
#define PROJWIRE_MAX_PAYLOAD (64u << 20) /* absolute; devices may say less */
#define PROJWIRE_BEGIN_SIZE (PROJWIRE_HEADER_SIZE + 16)
#define PROJWIRE_IMAGE_HEAD 8 /* image index, tile count; then the mask */
#define PROJWIRE_END_SIZE (PROJWIRE_HEADER_SIZE + 8)
#define PROJWIRE_DELTA_BEGIN_SIZE (PROJWIRE_HEADER_SIZE + 24)
#define PROJWIRE_EVENT_MAX (PROJWIRE_HEADER_SIZE + 24)

#define PROJWIRE_MAX_BUFFERS 4
#define PROJWIRE_MAX_TILES 65536 /* per image: 8192 x 8192 pixels */
#define PROJWIRE_NO_BUFFER 0xffffffffu

enum projwire_record_type {
	PROJWIRE_VOLUME_BEGIN = 0x01,
	PROJWIRE_IMAGE = 0x02,
	PROJWIRE_IMAGE_DELTA = 0x03, /* 1.1: changed tiles of one image */
	PROJWIRE_VOLUME_END = 0x04,
	PROJWIRE_DELTA_BEGIN = 0x05, /* 1.1: a volume built on the buffer's content */
	PROJWIRE_EV_SWAPPED = 0x81,
	PROJWIRE_EV_ERROR = 0x82,
};

enum projwire_request {
	PROJWIRE_REQ_GET_INFO = 0x01,
	PROJWIRE_REQ_GET_STATUS = 0x02,
	PROJWIRE_REQ_SET_BLANK = 0x10,
	PROJWIRE_REQ_SET_TIMING = 0x11,
	PROJWIRE_REQ_SWAP = 0x12,
	PROJWIRE_REQ_RESET_STREAM = 0x13,
	PROJWIRE_REQ_SWAP_HALF = 0x14, /* 1.2: SWAP from the next half-turn start */
};

/* bmRequestType: vendor request to the interface, device-to-host or not. */
#define PROJWIRE_RT_IN 0xc1
#define PROJWIRE_RT_OUT 0x41

/* Error codes in GET_STATUS.last_error and ERROR events. */
enum projwire_error {
	PROJWIRE_ERR_NONE = 0,
	PROJWIRE_ERR_REQUEST = 1,     /* bad control request */
	PROJWIRE_ERR_FRAMING = 2,     /* bad magic, type, flags or length; record out of place */
	PROJWIRE_ERR_IMAGE = 3,       /* image index, order, mask, tile content */
	PROJWIRE_ERR_CRC = 4,         /* VOLUME_END CRC or image count mismatch */
	PROJWIRE_ERR_BUSY = 5,        /* buffer shown, awaiting a swap, or a swap pending */
	PROJWIRE_ERR_NOT_READY = 6,   /* swap to a buffer with no valid volume */
	PROJWIRE_ERR_UNSUPPORTED = 7, /* reserved record type or request */
	PROJWIRE_ERR_NO_MEMORY = 8,
	PROJWIRE_ERR_ABORTED = 9, /* volume abandoned by RESET_STREAM or a new BEGIN */
};

/* Negative errno <-> wire error code (both directions of one table). */
uint32_t projwire_error_from_errno(int err);
int projwire_error_to_errno(uint32_t code);

/* CRC-32 (IEEE 802.3, as zlib's crc32): start with crc = 0. */
uint32_t projwire_crc32(uint32_t crc, const void *buf, size_t len);

/* ---- Control requests (EP0) ---- */

struct projwire_setup {
	uint8_t request_type, request;
	uint16_t value, index, length;
};

struct projwire_timing {
	uint64_t period_ns;
	int64_t index_ns;    /* host CLOCK_MONOTONIC of a revolution start */
	int64_t host_now_ns; /* host CLOCK_MONOTONIC when the request was built */
};

struct projwire_ctrl {
	enum projwire_request request;
	union {
		bool blank;                    /* SET_BLANK */
		uint32_t buffer;               /* SWAP, SWAP_HALF */
		struct projwire_timing timing; /* SET_TIMING */
	};
};

/* Host: the setup packet and OUT data stage of request c to interface iface.
 * Returns the OUT data stage length (0 for requests without one; the IN
 * requests expect setup.length bytes back). */
size_t projwire_ctrl_encode(const struct projwire_ctrl *c, uint16_t iface, uint8_t setup[PROJWIRE_SETUP_SIZE],
			    uint8_t data[PROJWIRE_CTRL_DATA_MAX]);

/* Device: parses and validates a request and its OUT data stage. Returns 0,
 * -EOPNOTSUPP for an unknown request, -EINVAL for a malformed one. */
int projwire_ctrl_decode(const uint8_t setup[PROJWIRE_SETUP_SIZE], const uint8_t *data, size_t len,
			 struct projwire_ctrl *out);

void projwire_setup_encode(const struct projwire_setup *s, uint8_t out[PROJWIRE_SETUP_SIZE]);
void projwire_setup_decode(const uint8_t in[PROJWIRE_SETUP_SIZE], struct projwire_setup *s);

#define PROJWIRE_INFO_MIRRORED 0x01

struct projwire_info {
	uint8_t version_major, version_minor;
	uint32_t width, height, images_per_rev, flags;
	float half_height, nominal_rpm;
	uint32_t buffers, tile_size, max_record, images_per_volume;
	uint64_t link_bytes_per_sec; /* 0 = unknown */
};

/* GET_INFO reply. Decode checks the major version, size and every field's
 * range (-EPROTO for another major version or size, -EINVAL otherwise). */
void projwire_info_encode(const struct projwire_info *info, uint8_t out[PROJWIRE_INFO_SIZE]);
int projwire_info_decode(const uint8_t *in, size_t len, struct projwire_info *out);

/* Whether a device of this info takes SWAP_HALF: version 1.2 or later and
 * mirrored (section 1). A host sends it to no other. */
bool projwire_info_half_turn_swaps(const struct projwire_info *info);

/* Between device info and geometry. */
void projwire_info_from_geometry(struct projwire_info *info, const struct geometry *g, uint32_t buffers,
				 uint64_t link_bytes_per_sec);
void projwire_info_to_geometry(const struct projwire_info *info, struct geometry *g);

#define PROJWIRE_STATUS_BLANKED 0x01
#define PROJWIRE_STATUS_TIMING 0x02       /* SET_TIMING received */
#define PROJWIRE_STATUS_PENDING 0x04      /* a swap awaits its revolution start */
#define PROJWIRE_STATUS_PENDING_HALF 0x08 /* 1.2: ... a half-turn start (SWAP_HALF) */

enum projwire_buffer_state {
	PROJWIRE_BUF_EMPTY = 0,   /* never written */
	PROJWIRE_BUF_WRITING = 1, /* a volume is being received */
	PROJWIRE_BUF_READY = 2,   /* a complete, CRC-checked volume */
	PROJWIRE_BUF_INVALID = 3, /* the last write failed: never shown */
};

struct projwire_status {
	uint32_t flags;
	uint32_t shown, pending; /* PROJWIRE_NO_BUFFER when none */
	uint64_t revolutions, swaps, underruns, bytes;
	uint32_t last_error, decode_errors;
	uint8_t buffer_state[PROJWIRE_MAX_BUFFERS];
};

/* GET_STATUS reply. Decode returns 0, -EPROTO (size) or -EINVAL. */
void projwire_status_encode(const struct projwire_status *st, uint8_t out[PROJWIRE_STATUS_SIZE]);
int projwire_status_decode(const uint8_t *in, size_t len, struct projwire_status *out);

/* ---- Bulk OUT records (host -> device) ---- */

/* Sizes include the record header. */
size_t projwire_image_size(const struct volume *vol, uint32_t k);
size_t projwire_volume_size(const struct volume *vol);

void projwire_begin_encode(uint8_t out[PROJWIRE_BEGIN_SIZE], uint32_t buffer, uint32_t image_count, uint64_t seq);
/* Writes image k's IMAGE record (projwire_image_size() bytes). */
size_t projwire_image_encode(const struct volume *vol, uint32_t k, uint8_t *out);
void projwire_end_encode(uint8_t out[PROJWIRE_END_SIZE], uint32_t image_records, uint32_t crc);
void projwire_delta_begin_encode(uint8_t out[PROJWIRE_DELTA_BEGIN_SIZE], uint32_t buffer, uint32_t image_count,
				 uint64_t seq, uint64_t base_seq);

/* The whole upload of vol into buffer: VOLUME_BEGIN, an IMAGE record for
 * each non-empty image, VOLUME_END. out has projwire_volume_size() bytes.
 * Returns the bytes written. */
size_t projwire_volume_encode(const struct volume *vol, uint32_t buffer, uint8_t *out);

/* An upload's form, and for a delta which tiles of each image differ
 * from the base, found once by projwire_upload_plan() and written by
 * projwire_upload_encode(), so that the two volumes are compared once.
 * Zero-initialise; the arrays grow to the volumes planned. */
struct projwire_delta {
	bool delta;      /* the form planned: a delta, else whole */
	uint32_t *tiles; /* per image: the tiles that differ */
	uint8_t *masks;  /* per image: which (the volume's mask_bytes each) */
	uint32_t images_cap;
	size_t masks_cap;
};
void projwire_delta_free(struct projwire_delta *d);

/* Plans the upload of vol into a buffer that holds base (NULL: empty or
 * unknown), for a version 1.1 device: *size is its exact size in the
 * smaller of two forms, a delta volume carrying only the tiles that
 * differ from base (an unchanged volume costs 48 bytes; d->delta set) or
 * the whole volume. Compares the volumes (about 0.5 ms for 9 MB at
 * perspecta), but not images whose stamps are equal and not 0
 * (volume.h), and, when differ is given (a mask of vol's mask_bytes per
 * image, image after image), not the contents of tiles both volumes
 * hold that it does not mark: the caller vouches that those are equal
 * (a tile one of them lacks is sent all the same). Returns 0 or -ENOMEM. */
int projwire_upload_plan(const struct volume *vol, const struct volume *base, const uint8_t *differ,
			 struct projwire_delta *d, size_t *size);
/* Writes the upload d plans for vol (and the same base) into out, which
 * has the planned size. Returns the bytes written. */
size_t projwire_upload_encode(const struct volume *vol, const struct volume *base, const struct projwire_delta *d,
			      uint32_t buffer, uint8_t *out);

/* ---- Bulk OUT decoder (device side) ---- */

struct projwire_sink {
	/* VOLUME_BEGIN (base_seq NULL) or DELTA_BEGIN for buffer: returns the
	 * volume to write into, or NULL with a negative errno in *err to refuse
	 * (-EBUSY for a buffer shown or awaiting a swap; for a delta, -ENODATA
	 * unless the buffer is ready and holds volume *base_seq). The decoder
	 * clears it for a whole volume and edits it in place for a delta. */
	struct volume *(*begin)(void *data, uint32_t buffer, uint64_t seq, const uint64_t *base_seq, int *err);
	/* The volume begun for buffer is complete and valid (err 0), or failed
	 * (negative errno: its contents are garbage and must never be shown).
	 * buffer is PROJWIRE_NO_BUFFER for an error outside a volume. */
	void (*end)(void *data, uint32_t buffer, int err);
};

struct projwire_decoder_stats {
	uint64_t bytes;   /* fed */
	uint64_t records; /* accepted */
	uint64_t volumes; /* completed with a good CRC */
	uint64_t errors;  /* rejections */
	uint64_t skipped; /* bytes discarded while resynchronising */
};

struct projwire_decoder;

/* A decoder for a device of geometry geom with buffers volume buffers,
 * accepting records of at most max_record payload bytes (0: the largest
 * this geometry needs). The sink must outlive the decoder. NULL + errno. */
struct projwire_decoder *projwire_decoder_create(const struct geometry *geom, uint32_t buffers, uint32_t max_record,
						 const struct projwire_sink *sink, void *data);
/* Accepts NULL. */
void projwire_decoder_destroy(struct projwire_decoder *d);

/* Feeds len bytes, split anywhere. After an error the decoder discards bytes
 * until the next VOLUME_BEGIN header. Returns 0, or the first error met in
 * these bytes (already reported to the sink and recovered from). */
int projwire_decoder_feed(struct projwire_decoder *d, const uint8_t *buf, size_t len);

/* RESET_STREAM: abandons a partial record and an open volume (-ECANCELED to
 * the sink); the next byte must start a record. */
void projwire_decoder_reset(struct projwire_decoder *d);

/* Largest IMAGE payload this geometry needs. */
uint32_t projwire_max_image_payload(const struct geometry *geom);

void projwire_decoder_get_stats(const struct projwire_decoder *d, struct projwire_decoder_stats *out);

/* ---- Bulk IN events (device -> host) ---- */

/* SWAPPED boundary flags (1.2; a 1.0 or 1.1 device sends 0). */
#define PROJWIRE_SWAPPED_HALF_TURN 0x01 /* time_ns is the start of image N/2, not of image 0 */

struct projwire_event {
	uint8_t type;      /* PROJWIRE_EV_* */
	uint32_t buffer;   /* PROJWIRE_NO_BUFFER when none */
	int64_t time_ns;   /* SWAPPED: the boundary it took effect at, host CLOCK_MONOTONIC */
	uint64_t seq;      /* volume sequence number of that buffer */
	uint32_t error;    /* ERROR: enum projwire_error */
	uint32_t boundary; /* SWAPPED: PROJWIRE_SWAPPED_* (decode keeps the bits it knows) */
};

/* Returns the bytes written, at most PROJWIRE_EVENT_MAX. */
size_t projwire_event_encode(const struct projwire_event *ev, uint8_t out[PROJWIRE_EVENT_MAX]);
/* Decodes the event at the start of in: the bytes it took, -EAGAIN when
 * in holds only part of it, -EPROTO when it is malformed. */
int projwire_event_decode(const uint8_t *in, size_t len, struct projwire_event *out);

#endif
