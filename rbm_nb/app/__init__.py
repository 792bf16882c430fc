"""rbm_nb.app"""
