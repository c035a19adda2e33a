/* test_directions.c — direction sets and (theta, phi) <-> vector conversions. */
#include "testutil.h"
#include "core/core.h" /* btf__dirset_ubo151 */

#include <math.h>
#include <stdlib.h>

static void ubo81_rings(void **state)
{
    (void)state;
    btf_dirset s;
    btf_error e = {0};
    TU_OK(btf_dirset_ubo81(&s, &e), &e);
    assert_int_equal(s.count, 81);
    assert_string_equal(s.name, "ubo81");
    static const int ring_count[] = {1, 6, 12, 18, 20, 24};
    static const double theta[] = {0, 15, 30, 45, 60, 75};
    int k = 0;
    for (int r = 0; r < 6; r++)
        for (int i = 0; i < ring_count[r]; i++, k++) {
            assert_true(s.dirs[k].theta == theta[r]);
            assert_true(fabs(s.dirs[k].phi - 360.0 * i / ring_count[r]) < 1e-12);
        }
    /* Every azimuth is a whole degree, as UBO2003 file names need. */
    for (int i = 0; i < 81; i++)
        assert_true(s.dirs[i].phi == floor(s.dirs[i].phi));
    btf_dirset_free(&s);
}

static void ubo151_rings(void **state)
{
    (void)state;
    btf_dirset s;
    btf_error e = {0};
    TU_OK(btf__dirset_ubo151(&s, &e), &e);
    assert_int_equal(s.count, 151);
    /* Ring 1 (theta 11) starts at phi 15 and has 6 azimuths 60 degrees apart. */
    assert_true(s.dirs[1].theta == 11.0 && s.dirs[1].phi == 15.0);
    assert_true(s.dirs[2].phi == 75.0);
    /* Ring 6 (theta 52.5, 18 azimuths) is offset by 7.5 degrees. */
    int k = 1 + 6 + 12 + 12 + 12 + 18;
    assert_true(s.dirs[k].theta == 52.5 && s.dirs[k].phi == 7.5);
    assert_true(s.dirs[150].theta == 75.0);
    btf_dirset_free(&s);
}

static void vector_round_trip(void **state)
{
    (void)state;
    for (int t = 0; t <= 90; t += 5)
        for (int p = 0; p < 360; p += 7) {
            btf_dir d = {t, t == 0 ? 0 : p};
            double v[3];
            btf_dir_to_vec(d, v);
            assert_true(fabs(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] - 1.0) < 1e-12);
            btf_dir back = btf_vec_to_dir(v);
            assert_true(btf_dir_angle(d, back) < 1e-9);
            assert_true(fabs(back.theta - d.theta) < 1e-9);
            if (t > 0)
                assert_true(fabs(back.phi - d.phi) < 1e-9);
        }
}

static void pole_horizon_and_degenerate(void **state)
{
    (void)state;
    double pole[3] = {0, 0, 1}, horizon[3] = {0, -1, 0}, zero[3] = {0, 0, 0};
    btf_dir d = btf_vec_to_dir(pole);
    assert_true(d.theta == 0.0 && d.phi == 0.0);
    d = btf_vec_to_dir(horizon);
    assert_true(fabs(d.theta - 90.0) < 1e-12 && fabs(d.phi - 270.0) < 1e-12);
    d = btf_vec_to_dir(zero);
    assert_true(d.theta == 0.0 && d.phi == 0.0);
    double inf[3] = {INFINITY, 0, 0};
    d = btf_vec_to_dir(inf);
    assert_true(isfinite(d.theta) && isfinite(d.phi));
    /* A non-unit vector gives the same direction. */
    double big[3] = {3e200, 0, 3e200};
    d = btf_vec_to_dir(big);
    assert_true(fabs(d.theta - 45.0) < 1e-9);
    /* Small angles are measured accurately (no acos cancellation). */
    btf_dir a = {0, 0}, b = {1e-7, 0};
    assert_true(fabs(btf_dir_angle(a, b) - 1e-7) < 1e-15);
    /* The azimuth of the pole does not matter. */
    btf_dir p1 = {0, 0}, p2 = {0, 123};
    assert_true(btf_dir_angle(p1, p2) < 1e-12);
}

static void find_and_custom_lists(void **state)
{
    (void)state;
    btf_dirset s;
    btf_error e = {0};
    TU_OK(btf_dirset_ubo81(&s, &e), &e);
    assert_int_equal(btf_dirset_find(&s, (btf_dir){75, 345}, 0.1), 80);
    assert_int_equal(btf_dirset_find(&s, (btf_dir){0, 200}, 0.1), 0);
    assert_int_equal(btf_dirset_find(&s, (btf_dir){80, 0}, 1.0), -1);
    /* A shuffled copy of the 81 directions is recognised as ubo81. */
    btf_dir shuffled[81];
    for (int i = 0; i < 81; i++)
        shuffled[i] = s.dirs[(i * 37) % 81];
    btf_dirset c;
    TU_OK(btf_dirset_from_list(&c, shuffled, 81, &e), &e);
    assert_string_equal(c.name, "ubo81");
    for (int i = 0; i < 81; i++)
        assert_true(btf_dir_angle(c.dirs[i], s.dirs[i]) < 1e-9);
    btf_dirset_free(&c);
    /* UBO2014's dome as whole-degree file names give it (23.5 -> 24, 7.5 -> 8):
     * still recognised (the rounding moves a direction by up to 0.69 degree,
     * inside BTF_DIR_NAME_TOLERANCE). */
    btf_dirset u151;
    TU_OK(btf__dirset_ubo151(&u151, &e), &e);
    btf_dir rounded[151];
    for (int i = 0; i < 151; i++)
        rounded[i] = (btf_dir){floor(u151.dirs[i].theta + 0.5), floor(u151.dirs[i].phi + 0.5)};
    TU_OK(btf_dirset_from_list(&c, rounded, 151, &e), &e);
    assert_string_equal(c.name, "ubo151");
    btf_dirset_free(&c);
    btf_dirset_free(&u151);
    /* Duplicates merge; phi is normalised; the order is ring by ring. */
    btf_dir list[] = {{30, 370}, {0, 45}, {30, 10}, {15, -90}, {0, 0}};
    TU_OK(btf_dirset_from_list(&c, list, 5, &e), &e);
    assert_string_equal(c.name, "custom");
    assert_int_equal(c.count, 3);
    assert_true(c.dirs[0].theta == 0 && c.dirs[1].theta == 15 && c.dirs[1].phi == 270);
    assert_true(fabs(c.dirs[2].phi - 10.0) < 1e-9);
    btf_dirset_free(&c);
    /* Out-of-range and non-finite directions are refused. */
    btf_dir bad[] = {{95, 0}};
    assert_int_equal(btf_dirset_from_list(&c, bad, 1, &e), BTF_E_ARG);
    btf_dir nan[] = {{NAN, 0}};
    assert_int_equal(btf_dirset_from_list(&c, nan, 1, &e), BTF_E_ARG);
    assert_int_equal(btf_dirset_from_list(&c, list, 0, &e), BTF_E_ARG);
    btf_dirset_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(ubo81_rings),
        cmocka_unit_test(ubo151_rings),
        cmocka_unit_test(vector_round_trip),
        cmocka_unit_test(pole_horizon_and_degenerate),
        cmocka_unit_test(find_and_custom_lists),
    };
    return cmocka_run_group_tests_name("directions", tests, NULL, NULL);
}
