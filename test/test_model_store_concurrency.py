"""ModelStore from several threads (the service answers while it fits): a refit swaps the model
in atomically, the old one answering until then, and the file always holds the served model."""
import threading

import numpy as np

from lpa_transfer.transfer.model_store import ModelStore
from two_link import correspondences


def test_a_refit_in_a_thread_swaps_atomically(tmp_path):
    store = ModelStore(tmp_path)
    source, target = correspondences(300, seed=1)
    test = correspondences(200, seed=2)[0]
    old = store.fit("a->b", "pa", source, target).transfer(test)
    big_source, big_target = correspondences(8000, seed=3)
    refit = threading.Thread(target=store.fit, args=("a->b", "lpa", big_source, big_target),
                             kwargs=dict(n_min=10, c_min=0.0, n_init=1))
    refit.start()
    answers = []
    while refit.is_alive():
        answers.append(store.transfer("a->b", test))
    refit.join()
    new = store.get("a->b").transfer(test)
    assert not np.array_equal(old, new)
    kinds = ["old" if np.array_equal(a, old) else "new" if np.array_equal(a, new) else "other"
             for a in answers]
    assert kinds.count("old") >= 3 and "other" not in kinds, kinds
    assert kinds == sorted(kinds, key=["old", "new"].index)   # old ones, then new ones
    assert np.array_equal(ModelStore(tmp_path).transfer("a->b", test), new)


def test_concurrent_fits_and_deletes_leave_file_and_memory_in_step(tmp_path):
    store = ModelStore(tmp_path)
    source, target = correspondences(300, seed=1)
    test = correspondences(50, seed=2)[0]

    def work(seed):
        for i in range(5):
            store.fit(f"id{seed % 2}", "lpa", source, target, random_state=seed * 10 + i)
            if i == 2 and seed % 2:
                try:
                    store.delete(f"id{seed % 2}")
                except ValueError:            # the other thread deleted it first
                    pass

    threads = [threading.Thread(target=work, args=(seed,)) for seed in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    reloaded = ModelStore(tmp_path)
    assert reloaded.ids() == store.ids()
    for model_id in store.ids():
        assert np.array_equal(reloaded.transfer(model_id, test), store.transfer(model_id, test))
