import pytest

from mission.language.units import parse_duration, parse_percent


@pytest.mark.parametrize("text, seconds", [("90s", 90), ("15min", 900), ("3h", 10800), ("1h30min", 5400),
                                           ("250ms", 0.25), (42, 42), ("2 h", 7200)])
def test_durations_are_read_in_seconds(text, seconds):
    assert parse_duration(text) == pytest.approx(seconds)


@pytest.mark.parametrize("text", ["15 minutes", "abc", "-5s", -3, "", True])
def test_bad_durations_are_refused(text):
    with pytest.raises(ValueError):
        parse_duration(text)


def test_percentages_accept_a_sign_or_a_bare_number():
    assert parse_percent("20%") == 20.0
    assert parse_percent(12.5) == 12.5


@pytest.mark.parametrize("text", ["120%", "twenty", -1, "20"])
def test_bad_percentages_are_refused(text):
    with pytest.raises(ValueError):
        parse_percent(text)
