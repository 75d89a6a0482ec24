import os

from prefect.task_runners import ThreadPoolTaskRunner

from flows.cpu_shares import _runner_cpus, task_cpu_share


def test_thread_pool_slots_bound_concurrency():
    cores = os.cpu_count() or 1
    assert _runner_cpus(ThreadPoolTaskRunner(max_workers=1)) == (cores, 1)
    assert _runner_cpus(ThreadPoolTaskRunner(max_workers=64)) == (cores, cores)


def test_outside_a_flow_one_task_gets_every_core():
    cores = os.cpu_count() or 1
    assert task_cpu_share(1) == cores
    assert task_cpu_share(100) == cores  # no runner: tasks run one at a time

