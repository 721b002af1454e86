/* daemon/idmap: random inserts, lookups and removals against a plain array,
 * with ids chosen to collide, so backward-shift deletion is exercised. */
#include <stdint.h>
#include <stdlib.h>

#include "check.h"
#include "idmap.h"

#define IDS 5000

int main(void)
{
	static uint32_t ids[IDS];
	static char present[IDS];
	struct idmap map = { 0 };
	srand(3);
	for (int i = 0; i < IDS; i++)
		ids[i] = (uint32_t)(i % 7 == 0 ? (i + 1) * 4096 : 2 + rand() % 100000000) | 1u;
	for (int round = 0; round < 200000; round++) {
		int i = rand() % IDS;
		if (present[i]) {
			CHECK(idmap_remove(&map, ids[i]) == &ids[i]);
			present[i] = 0;
		} else if (!idmap_get(&map, ids[i])) {
			CHECK(idmap_insert(&map, ids[i], &ids[i]) == 0);
			present[i] = 1;
		}
		if (round % 1000 == 0) {
			uint32_t n = 0;
			for (int j = 0; j < IDS; j++) {
				if (!present[j])
					continue;
				CHECK(idmap_get(&map, ids[j]) == &ids[j]);
				n++;
			}
			CHECK(n == map.count);
		}
	}
	CHECK(idmap_get(&map, 0) == NULL && idmap_remove(&map, 0) == NULL);
	idmap_finish(&map);
	return check_done();
}
