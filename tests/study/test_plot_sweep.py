"""``plot_sweep``: numeric parameters on a numeric axis, list- and string-valued ones
(``rom.orders``, ``rom.nf = "auto"``, ``sensors.rows``) as categories."""

import numpy as np

from casflutter.study import plot_sweep

ORDERS = ([3, 1, 1, 1, 2, 2], [2, 1, 1, 1, 2, 2], [3, 1, 1, 1, 2, 2], [4, 1, 1, 1, 2, 2])
NF = (15, "auto", "auto", 15)
VF = (1.2, 1.1, 1.25, None)


def _rows():
    return [{"key": str(k), "status": "ok" if vf is not None else "failed",
             "rom.orders": o, "rom.nf": nf, "controller.order": k % 2 + 1, "Vf_rom": vf}
            for k, (o, nf, vf) in enumerate(zip(ORDERS, NF, VF))]


def test_list_valued_parameter_is_categorical():
    fig = plot_sweep(_rows(), ["rom.orders", "rom.nf", "controller.order"], ["Vf_rom"])
    ax_orders, ax_nf, ax_num = fig.axes
    labels = ["[3, 1, 1, 1, 2, 2]", "[2, 1, 1, 1, 2, 2]", "[4, 1, 1, 1, 2, 2]"]
    assert [t.get_text() for t in ax_orders.get_xticklabels()] == labels
    ok, failed = ax_orders.lines[0], ax_orders.lines[1]
    # the three successful points at their category (the first and third share one)
    np.testing.assert_array_equal(ok.get_xdata(), [0.0, 1.0, 0.0])
    np.testing.assert_array_equal(ok.get_ydata(), [1.2, 1.1, 1.25])
    np.testing.assert_array_equal(failed.get_xdata(), [2.0])   # the failed point's orders
    # a mix of numbers and strings is categorical too, labelled as given
    assert [t.get_text() for t in ax_nf.get_xticklabels()] == ["15", "auto"]
    np.testing.assert_array_equal(ax_nf.lines[0].get_xdata(), [0.0, 1.0, 1.0])
    # a numeric parameter keeps its numeric axis (values as x)
    np.testing.assert_array_equal(ax_num.lines[0].get_xdata(), [1.0, 2.0, 1.0])


def test_nested_rows_parameter_is_categorical():
    R1 = [[0.1299, -0.0006, -0.2866, -0.113, 0.0766], [-0.0021, 0.1364, 0.0141, 0.0021, -0.002]]
    R2 = [R1[1]]
    rows = [{"key": "a", "status": "ok", "sensors.rows": R1, "gamma": 3.0},
            {"key": "b", "status": "ok", "sensors.rows": R2, "gamma": 5.0}]
    fig = plot_sweep(rows, ["sensors.rows"], ["gamma"])
    (ax,) = fig.axes
    np.testing.assert_array_equal(ax.lines[0].get_xdata(), [0.0, 1.0])
    # long labels are cut and numbered, so the two ticks stay distinct
    assert [t.get_text() for t in ax.get_xticklabels()] == [
        "1: [[0.1299, -0.0006,…", "2: [[-0.0021, 0.1364,…"]
