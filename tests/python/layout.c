/* The layout of spindle.h's structures as the C compiler sees it, for
 * tests/python/test_layout.py to compare with the binding's ctypes
 * declarations (python/spindle/_lib.py): one line per structure
 * ("NAME size SIZE") and per field ("NAME.FIELD OFFSET SIZE"). */
#include <stddef.h>
#include <stdio.h>

#include <spindle/spindle.h>

#define STRUCT(s) printf("%s size %zu\n", #s, sizeof(struct s))
#define FIELD(s, f) printf("%s.%s %zu %zu\n", #s, #f, offsetof(struct s, f), sizeof(((struct s *)0)->f))

int main(void)
{
	STRUCT(spindle_device_info);
	FIELD(spindle_device_info, width);
	FIELD(spindle_device_info, height);
	FIELD(spindle_device_info, images_per_rev);
	FIELD(spindle_device_info, mirrored);
	FIELD(spindle_device_info, half_height);
	FIELD(spindle_device_info, rpm);
	FIELD(spindle_device_info, name);

	STRUCT(spindle_limits);
	FIELD(spindle_limits, refused_clients);
	FIELD(spindle_limits, refused_per_user);
	FIELD(spindle_limits, refused_incomplete);
	FIELD(spindle_limits, handshake_timeouts);
	FIELD(spindle_limits, accept_pauses);
	FIELD(spindle_limits, clients_in_handshake);
	FIELD(spindle_limits, fds);
	FIELD(spindle_limits, fd_limit);
	FIELD(spindle_limits, memory_used);
	FIELD(spindle_limits, memory_budget);
	FIELD(spindle_limits, refused_memory);
	FIELD(spindle_limits, mappings);
	FIELD(spindle_limits, mapping_budget);
	FIELD(spindle_limits, refused_mappings);

	STRUCT(spindle_service);
	FIELD(spindle_service, watchdog_ms);
	FIELD(spindle_service, watchdog_fed);
	FIELD(spindle_service, watchdog_withheld);
	FIELD(spindle_service, max_client_fds);
	FIELD(spindle_service, refused_fds);

	STRUCT(spindle_composition);
	FIELD(spindle_composition, cache);
	FIELD(spindle_composition, objects);
	FIELD(spindle_composition, cached);
	FIELD(spindle_composition, cache_bytes);
	FIELD(spindle_composition, cache_budget);
	FIELD(spindle_composition, hits);
	FIELD(spindle_composition, misses);
	FIELD(spindle_composition, creates);
	FIELD(spindle_composition, invalidations);
	FIELD(spindle_composition, evictions);
	FIELD(spindle_composition, objects_rendered);
	FIELD(spindle_composition, objects_reused);
	FIELD(spindle_composition, render_us);
	FIELD(spindle_composition, compose_us);

	STRUCT(spindle_status);
	FIELD(spindle_status, rpm);
	FIELD(spindle_status, locked);
	FIELD(spindle_status, blanked);
	FIELD(spindle_status, projector_present);
	FIELD(spindle_status, volumes_shown);
	FIELD(spindle_status, clients);
	FIELD(spindle_status, underruns);
	FIELD(spindle_status, volumes_rendered);
	FIELD(spindle_status, volumes_skipped);
	FIELD(spindle_status, bytes_uploaded);
	FIELD(spindle_status, render_us);
	FIELD(spindle_status, jitter_us);
	FIELD(spindle_status, missed_pulses);
	FIELD(spindle_status, upload_rate);
	FIELD(spindle_status, index_error_us);
	FIELD(spindle_status, angle_error_p99);
	FIELD(spindle_status, angle_error_max);
	FIELD(spindle_status, limits_known);
	FIELD(spindle_status, limits);
	FIELD(spindle_status, service);
	FIELD(spindle_status, composition_known);
	FIELD(spindle_status, composition);

	STRUCT(spindle_state);
	FIELD(spindle_state, locked);
	FIELD(spindle_state, blanked);
	FIELD(spindle_state, projector_present);
	FIELD(spindle_state, rpm);

	STRUCT(spindle_frame);
	FIELD(spindle_frame, volume_seq);
	FIELD(spindle_frame, time_ns);

	STRUCT(spindle_listener);
	FIELD(spindle_listener, state);
	FIELD(spindle_listener, refused);

	STRUCT(spindle_calibration);
	FIELD(spindle_calibration, phase_offset);
	FIELD(spindle_calibration, axis_offset_u);
	FIELD(spindle_calibration, axis_offset_v);
	FIELD(spindle_calibration, vertical_scale);
	FIELD(spindle_calibration, vertical_offset);

	/* The enums the binding passes as int. */
	printf("enum.size %zu\n", sizeof(enum spindle_mode));
	printf("SPINDLE_INLINE_MAX %d\n", SPINDLE_INLINE_MAX);
	printf("SPINDLE_PROTOCOL_VERSION %d\n", SPINDLE_PROTOCOL_VERSION);
	printf("enum.volume_type.size %zu\n", sizeof(enum spindle_volume_type));
	printf("enum.sampling.size %zu\n", sizeof(enum spindle_sampling));
	printf("SPINDLE_VOLUME_U8 %d\n", SPINDLE_VOLUME_U8);
	printf("SPINDLE_VOLUME_U16 %d\n", SPINDLE_VOLUME_U16);
	printf("SPINDLE_VOLUME_I16 %d\n", SPINDLE_VOLUME_I16);
	printf("SPINDLE_VOLUME_F32 %d\n", SPINDLE_VOLUME_F32);
	printf("SPINDLE_VOLUME_RGBA8 %d\n", SPINDLE_VOLUME_RGBA8);
	printf("SPINDLE_NEAREST %d\n", SPINDLE_NEAREST);
	printf("SPINDLE_TRILINEAR %d\n", SPINDLE_TRILINEAR);
	return 0;
}
