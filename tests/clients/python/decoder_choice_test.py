"""Which decoder the package picks (skinstream/decoder_choice.py): the system's libraries when asked
for and they load, numpy otherwise, which always works; and decoders() saying so, with how to
get a library numpy stands in for."""
import ctypes.util
import os
import sys
import unittest
from unittest import mock

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
from support.python_clients import CLIENT_LIBRARY  # noqa: E402
from support.subscriber_models import random_body  # noqa: E402
import skinstream  # noqa: E402
from skinstream import client_library, decoder_choice, protocol as wire  # noqa: E402
from skinstream.meshoptimizer_library import find_meshoptimizer  # noqa: E402


def with_client_library(path, work):
    """work() with SKINSTREAM_CLIENT_LIBRARY set to `path`, the package looking for it afresh."""
    saved = os.environ.get(client_library.ENVIRONMENT)
    os.environ[client_library.ENVIRONMENT] = path
    client_library.find_client_library.cache_clear()
    try:
        return work()
    finally:
        if saved is None:
            del os.environ[client_library.ENVIRONMENT]
        else:
            os.environ[client_library.ENVIRONMENT] = saved
        client_library.find_client_library.cache_clear()


class ChoosingADecoder(unittest.TestCase):
    def setUp(self):
        body = random_body(1, vertices=100)
        self.payload = body.model_payload()
        self.model, self.faces = wire.Model(self.payload), body.faces

    def test_numpy_when_the_libraries_are_not_wanted(self):
        self.assertEqual(decoder_choice.parameter_evaluator(self.model, self.payload, self.faces, libraries=False).name, 'numpy')
        self.assertEqual(decoder_choice.compressed_decoder(100, libraries=False).name, 'numpy')

    def test_numpy_when_the_client_library_does_not_load_and_how_to_get_it(self):
        def choose():
            return decoder_choice.parameter_evaluator(self.model, self.payload, self.faces).name, skinstream.decoders()['parameters']
        name, line = with_client_library('/nonexistent/libskinstream_client.so.0', choose)
        self.assertEqual(name, 'numpy')
        self.assertRegex(line, '^numpy; /nonexistent/libskinstream_client.so.0 does not load: ')

    def test_numpy_when_there_is_no_meshoptimizer_and_which_package_has_it(self):
        find_meshoptimizer.cache_clear()
        try:
            with mock.patch.object(ctypes.util, 'find_library', return_value=None):
                name, line = decoder_choice.compressed_decoder(100).name, skinstream.decoders()['compressed']
        finally:
            find_meshoptimizer.cache_clear()
        self.assertEqual(name, 'numpy')
        self.assertEqual(line, 'numpy; libmeshoptimizer not found (Debian: apt-get install libmeshoptimizer2d)')

    def test_the_libraries_when_they_load(self):
        if os.path.exists(CLIENT_LIBRARY):
            def choose():
                return decoder_choice.parameter_evaluator(self.model, self.payload, self.faces).name, skinstream.decoders()['parameters']
            self.assertEqual(with_client_library(CLIENT_LIBRARY, choose), ('libskinstream_client', f'libskinstream_client ({CLIENT_LIBRARY})'))
        meshoptimizer, line = find_meshoptimizer()
        expected = 'numpy' if meshoptimizer is None else 'libmeshoptimizer'
        self.assertEqual(decoder_choice.compressed_decoder(100).name, expected)
        self.assertTrue(skinstream.decoders()['compressed'].startswith(expected), line)
        self.assertEqual(skinstream.decoders()['float'], 'numpy (views of the message)')


if __name__ == '__main__':
    unittest.main(verbosity=2)
