"""The renderer's resources kept in step with their sources (`cloudcore.runtime.derived`)."""

import pytest

from cloudcore.runtime.derived import Derived


class Resource:
    def __init__(self, source, made):
        self.source, self.closed = source, False
        made.append(self)

    def close(self):
        self.closed = True


def test_a_derived_resource_is_made_again_only_when_its_source_changes_the_old_closed_first():
    made = []
    derived = Derived(lambda source, made: Resource(source, made), Resource.close)
    assert derived.follow(("terrain", 1), made) and not derived.follow(("terrain", 1), made)
    first = derived.value
    assert derived.follow(("terrain", 2), made) and first.closed and not derived.value.closed
    assert [resource.source for resource in made] == [("terrain", 1), ("terrain", 2)]


def test_a_derived_resource_that_fails_to_build_leaves_none_and_is_tried_again():
    def fail(source):
        raise RuntimeError("no context")

    derived = Derived(lambda source: Resource(source, []), Resource.close)
    derived.follow(1)
    old = derived.value
    derived._make = fail
    with pytest.raises(RuntimeError):
        derived.follow(2)
    assert old.closed and derived.value is None and not derived.made
    with pytest.raises(RuntimeError):
        derived.follow(2)  # the same source again: not made, so tried again


def test_without_close_the_old_resource_is_there_while_the_new_one_is_made():
    derived = Derived(lambda source: (source, derived.value))
    derived.follow("a")
    derived.follow("b")
    assert derived.value == ("b", ("a", None))
